//! A small isoparametric Lagrange finite-element solver for `−Δu = f`, `u = g` on the
//! boundary, on a triangle mesh as gmsh delivers it (corners counter-clockwise or not,
//! then the high-order nodes in gmsh order: type 2 / 9 / 21 = geometry order 1 / 2 / 3),
//! with solution elements of degree `P` = 1, 2 or 3 (not necessarily the geometry order:
//! P2 on a cubic mesh is superparametric). Independent of the library: it shares no code
//! with `src/` (its basis, quadrature and node order are written here from their
//! definitions), so the convergence test measures the mesh, not the mesher's own
//! element code.
//!
//! - Basis: the Lagrange basis of degree `n` on the equispaced barycentric lattice
//!   `a = (a0, a1, a2)`, `a0 + a1 + a2 = n`, in the product form
//!   `φ_a(λ) = Π_i Π_{k < a_i} (n λ_i − k) / (k + 1)` (1 at its lattice point, 0 at the
//!   others), listed in gmsh order (corners; edge 0→1, 1→2, 2→0 nodes from the edge's
//!   first corner; the interior node).
//! - Quadrature: the collapsed-square (Duffy) product of Gauss–Legendre rules on `[0, 1]`:
//!   `ξ = s`, `η = t (1 − s)`, weight `w_s w_t (1 − s)`; `m` points per direction
//!   integrate polynomials of degree `2m − 2` in `(ξ, η)` exactly. The Gauss–Legendre
//!   nodes are the roots of the Legendre polynomial `P_m`, found by Newton's iteration
//!   from the Chebyshev guesses `cos(π (i + 3/4) / (m + 1/2))`, with weights
//!   `2 / ((1 − x²) P_m'(x)²)` (Abramowitz & Stegun 25.4.29; Golub & Welsch).
//! - Degrees of freedom: one per mesh corner, `P − 1` per mesh edge (keyed by its corner
//!   node ids, ordered from the lower id), `(P − 1)(P − 2)/2` per element. Boundary edges
//!   (used by one element) and their corners carry the Dirichlet data `g` sampled at the
//!   degrees of freedom's physical positions (the geometry map of their reference
//!   points).
//! - Solve: the stiffness matrix of the free degrees of freedom in CSR form, Jacobi-
//!   preconditioned conjugate gradients (symmetric positive definite).
//! - Errors: `‖u − u_h‖_L2` and `|u − u_h|_H1` by the quadrature on the curved elements.

use std::collections::HashMap;

/// A problem with a known solution.
pub(crate) struct Problem<'a> {
    /// The exact solution (also the Dirichlet data).
    pub(crate) u: &'a dyn Fn(f64, f64) -> f64,
    /// Its gradient.
    pub(crate) grad: &'a dyn Fn(f64, f64) -> [f64; 2],
    /// The source `f = −Δu`.
    pub(crate) f: &'a dyn Fn(f64, f64) -> f64,
}

/// What one solve measured.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Solution {
    /// `‖u − u_h‖_L2`.
    pub(crate) l2: f64,
    /// `|u − u_h|_H1`.
    pub(crate) h1: f64,
    /// Area of the mesh (the integral of `|det J|`).
    pub(crate) area: f64,
    /// Number of elements.
    pub(crate) elements: usize,
    /// Number of degrees of freedom (free and Dirichlet).
    pub(crate) dofs: usize,
    /// Conjugate-gradient iterations.
    pub(crate) iterations: usize,
    /// Smallest `det J` (signed to the element's orientation) at a quadrature point,
    /// relative to the element's corner `det J`.
    pub(crate) min_det_ratio: f64,
}

/// Number of nodes of a degree-`n` triangle.
pub(crate) fn node_count(n: usize) -> usize {
    (n + 1) * (n + 2) / 2
}

/// The barycentric lattice indices `(a0, a1, a2)` of the degree-`n` nodes, in gmsh order.
pub(crate) fn gmsh_lattice(n: usize) -> Vec<[usize; 3]> {
    let mut v = vec![[n, 0, 0], [0, n, 0], [0, 0, n]];
    if n == 0 {
        return vec![[0, 0, 0]];
    }
    // edges 0→1, 1→2, 2→0, from the first corner
    for j in 1..n {
        v.push([n - j, j, 0]);
    }
    for j in 1..n {
        v.push([0, n - j, j]);
    }
    for j in 1..n {
        v.push([j, 0, n - j]);
    }
    match n {
        1 | 2 => {}
        3 => v.push([1, 1, 1]),
        _ => panic!("degree {n} not supported"),
    }
    v
}

/// Values and reference gradients `(∂/∂ξ, ∂/∂η)` of the degree-`n` Lagrange basis at
/// `(ξ, η)`, in the order of `lattice`.
pub(crate) fn basis(n: usize, lattice: &[[usize; 3]], xi: f64, eta: f64) -> Vec<(f64, [f64; 2])> {
    let l = [1.0 - xi - eta, xi, eta];
    let nf = n as f64;
    // factor f(a, x) = Π_{k<a} (n x − k)/(k + 1) and its derivative
    let factor = |a: usize, x: f64| -> (f64, f64) {
        let mut v = 1.0;
        let mut d = 0.0;
        for k in 0..a {
            let c = (nf * x - k as f64) / (k + 1) as f64;
            let dc = nf / (k + 1) as f64;
            d = d * c + v * dc;
            v *= c;
        }
        (v, d)
    };
    lattice
        .iter()
        .map(|a| {
            let f: Vec<(f64, f64)> = (0..3).map(|i| factor(a[i], l[i])).collect();
            let val = f[0].0 * f[1].0 * f[2].0;
            let dl = [
                f[0].1 * f[1].0 * f[2].0,
                f[0].0 * f[1].1 * f[2].0,
                f[0].0 * f[1].0 * f[2].1,
            ];
            // λ0 = 1 − ξ − η, λ1 = ξ, λ2 = η
            (val, [dl[1] - dl[0], dl[2] - dl[0]])
        })
        .collect()
}

/// Gauss–Legendre nodes and weights on `[0, 1]` with `m` points.
pub(crate) fn gauss_legendre(m: usize) -> Vec<(f64, f64)> {
    let mf = m as f64;
    (0..m)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (mf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // P_m(x) and P_m'(x) by the three-term recurrence
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=m {
                    let kf = k as f64;
                    let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
                    p0 = p1;
                    p1 = p2;
                }
                let p = if m == 0 { 1.0 } else { p1 };
                let pm1 = if m == 1 { 1.0 } else { p0 };
                dp = mf * (x * p - pm1) / (x * x - 1.0);
                let dx = p / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            (0.5 * (1.0 + x), 0.5 * w)
        })
        .collect()
}

/// Quadrature on the reference triangle `(0,0), (1,0), (0,1)`: points `(ξ, η)` and
/// weights (summing to 1/2), exact for polynomials of degree `2m − 2`.
pub(crate) fn triangle_rule(m: usize) -> Vec<([f64; 2], f64)> {
    let g = gauss_legendre(m);
    let mut r = Vec::with_capacity(m * m);
    for &(s, ws) in &g {
        for &(t, wt) in &g {
            r.push(([s, t * (1.0 - s)], ws * wt * (1.0 - s)));
        }
    }
    r
}

/// The geometry order of a triangle with `k` nodes.
pub(crate) fn order_of_nodes(k: usize) -> usize {
    match k {
        3 => 1,
        6 => 2,
        10 => 3,
        _ => panic!("{k} nodes is not a gmsh triangle of order ≤ 3"),
    }
}

/// Points per direction of the quadrature: degree `2·10 − 2 = 18`, ample for the
/// degree-≤ 3 solution products on elements whose `det J` is a polynomial of degree ≤ 4.
const QUAD_POINTS: usize = 10;

/// Solve `problem` with degree-`p` elements on the mesh `nodes` / `triangles` (each
/// triangle lists its gmsh-ordered node indices; all triangles have the same order).
pub(crate) fn solve(
    nodes: &[[f64; 2]],
    triangles: &[Vec<u32>],
    p: usize,
    problem: &Problem<'_>,
) -> Solution {
    let geo = order_of_nodes(triangles[0].len());
    let geo_lat = gmsh_lattice(geo);
    let sol_lat = gmsh_lattice(p);
    let rule = triangle_rule(QUAD_POINTS);
    let geo_at: Vec<Vec<(f64, [f64; 2])>> = rule
        .iter()
        .map(|(x, _)| basis(geo, &geo_lat, x[0], x[1]))
        .collect();
    let sol_at: Vec<Vec<(f64, [f64; 2])>> = rule
        .iter()
        .map(|(x, _)| basis(p, &sol_lat, x[0], x[1]))
        .collect();

    // Degrees of freedom.
    let mut vertex_dof: HashMap<u32, usize> = HashMap::new();
    let mut edge_dof: HashMap<(u32, u32), usize> = HashMap::new();
    let mut edge_uses: HashMap<(u32, u32), usize> = HashMap::new();
    let mut count = 0usize;
    let mut elem_dofs: Vec<Vec<usize>> = Vec::with_capacity(triangles.len());
    const EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];
    for t in triangles {
        assert_eq!(order_of_nodes(t.len()), geo, "mixed element orders");
        let mut d = Vec::with_capacity(node_count(p));
        for &c in &t[..3] {
            let e = vertex_dof.entry(c).or_insert_with(|| {
                count += 1;
                count - 1
            });
            d.push(*e);
        }
        for [i, j] in EDGES {
            let (a, b) = (t[i], t[j]);
            let key = (a.min(b), a.max(b));
            *edge_uses.entry(key).or_insert(0) += 1;
            let base = *edge_dof.entry(key).or_insert_with(|| {
                count += p - 1;
                count - (p - 1)
            });
            for k in 0..p - 1 {
                // k-th node from this element's first corner; the shared numbering
                // runs from the lower node id
                let g = if a < b { base + k } else { base + (p - 2 - k) };
                d.push(g);
            }
        }
        for _ in 0..(p - 1) * p.saturating_sub(2) / 2 {
            d.push(count);
            count += 1;
        }
        debug_assert_eq!(d.len(), node_count(p));
        elem_dofs.push(d);
    }

    // Dirichlet degrees of freedom and their values: the geometry map at the reference
    // points of the degrees of freedom on boundary edges.
    let mut fixed: Vec<Option<f64>> = vec![None; count];
    for (t, d) in triangles.iter().zip(&elem_dofs) {
        for (e, [i, j]) in EDGES.into_iter().enumerate() {
            let key = (t[i].min(t[j]), t[i].max(t[j]));
            if edge_uses[&key] != 1 {
                continue;
            }
            let mut local = vec![i, j];
            local.extend((0..p - 1).map(|k| 3 + e * (p - 1) + k));
            for li in local {
                let a = sol_lat[li];
                let (xi, eta) = (a[1] as f64 / p as f64, a[2] as f64 / p as f64);
                let x = map(nodes, t, geo, &geo_lat, xi, eta);
                fixed[d[li]] = Some((problem.u)(x[0], x[1]));
            }
        }
    }
    let mut free_index = vec![usize::MAX; count];
    let mut nfree = 0;
    for (g, f) in fixed.iter().enumerate() {
        if f.is_none() {
            free_index[g] = nfree;
            nfree += 1;
        }
    }

    // Assembly.
    let nl = node_count(p);
    let mut triplets: Vec<(usize, usize, f64)> = Vec::new();
    let mut rhs = vec![0.0; nfree];
    let mut area = 0.0;
    let mut min_det_ratio = f64::INFINITY;
    for (t, d) in triangles.iter().zip(&elem_dofs) {
        let xs: Vec<[f64; 2]> = t.iter().map(|&i| nodes[i as usize]).collect();
        let mut ke = vec![0.0; nl * nl];
        let mut fe = vec![0.0; nl];
        let corner_det = {
            let (a, b, c) = (xs[0], xs[1], xs[2]);
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        };
        for (q, (_, w)) in rule.iter().enumerate() {
            let (x, jac) = jacobian(&xs, &geo_at[q]);
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            min_det_ratio = min_det_ratio.min(det / corner_det);
            let wd = w * det.abs();
            area += wd;
            let grads = physical_gradients(&sol_at[q], jac, det);
            let fx = (problem.f)(x[0], x[1]);
            for a in 0..nl {
                fe[a] += wd * fx * sol_at[q][a].0;
                for b in 0..nl {
                    ke[a * nl + b] += wd * (grads[a][0] * grads[b][0] + grads[a][1] * grads[b][1]);
                }
            }
        }
        for a in 0..nl {
            let ga = free_index[d[a]];
            if ga == usize::MAX {
                continue;
            }
            rhs[ga] += fe[a];
            for b in 0..nl {
                match fixed[d[b]] {
                    Some(v) => rhs[ga] -= ke[a * nl + b] * v,
                    None => triplets.push((ga, free_index[d[b]], ke[a * nl + b])),
                }
            }
        }
    }
    let k = Csr::from_triplets(nfree, triplets);
    let (x, iterations) = k.pcg(&rhs, 1e-13, 20 * nfree + 100);
    let value = |g: usize| fixed[g].unwrap_or_else(|| x[free_index[g]]);

    // Errors.
    let (mut l2, mut h1) = (0.0, 0.0);
    for (t, d) in triangles.iter().zip(&elem_dofs) {
        let xs: Vec<[f64; 2]> = t.iter().map(|&i| nodes[i as usize]).collect();
        let coef: Vec<f64> = d.iter().map(|&g| value(g)).collect();
        for (q, (_, w)) in rule.iter().enumerate() {
            let (x, jac) = jacobian(&xs, &geo_at[q]);
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            let grads = physical_gradients(&sol_at[q], jac, det);
            let mut uh = 0.0;
            let mut gh = [0.0; 2];
            for a in 0..nl {
                uh += coef[a] * sol_at[q][a].0;
                gh[0] += coef[a] * grads[a][0];
                gh[1] += coef[a] * grads[a][1];
            }
            let ge = (problem.grad)(x[0], x[1]);
            let wd = w * det.abs();
            l2 += wd * ((problem.u)(x[0], x[1]) - uh).powi(2);
            h1 += wd * ((ge[0] - gh[0]).powi(2) + (ge[1] - gh[1]).powi(2));
        }
    }
    Solution {
        l2: l2.sqrt(),
        h1: h1.sqrt(),
        area,
        elements: triangles.len(),
        dofs: count,
        iterations,
        min_det_ratio,
    }
}

/// The geometry map of triangle `t` at `(ξ, η)`.
fn map(
    nodes: &[[f64; 2]],
    t: &[u32],
    geo: usize,
    lat: &[[usize; 3]],
    xi: f64,
    eta: f64,
) -> [f64; 2] {
    let b = basis(geo, lat, xi, eta);
    let mut x = [0.0; 2];
    for (&i, (v, _)) in t.iter().zip(&b) {
        x[0] += v * nodes[i as usize][0];
        x[1] += v * nodes[i as usize][1];
    }
    x
}

/// The point and the Jacobian `[[∂x/∂ξ, ∂x/∂η], [∂y/∂ξ, ∂y/∂η]]` of the element with
/// nodes `xs` where the geometry basis takes `b`.
fn jacobian(xs: &[[f64; 2]], b: &[(f64, [f64; 2])]) -> ([f64; 2], [[f64; 2]; 2]) {
    let mut x = [0.0; 2];
    let mut j = [[0.0; 2]; 2];
    for (p, (v, g)) in xs.iter().zip(b) {
        for r in 0..2 {
            x[r] += v * p[r];
            j[r][0] += g[0] * p[r];
            j[r][1] += g[1] * p[r];
        }
    }
    (x, j)
}

/// Physical gradients `J⁻ᵀ ∇̂φ` of the basis values `b`.
fn physical_gradients(b: &[(f64, [f64; 2])], j: [[f64; 2]; 2], det: f64) -> Vec<[f64; 2]> {
    b.iter()
        .map(|(_, g)| {
            // J⁻ᵀ = (1/det) [[j11, −j10], [−j01, j00]]
            [
                (j[1][1] * g[0] - j[1][0] * g[1]) / det,
                (-j[0][1] * g[0] + j[0][0] * g[1]) / det,
            ]
        })
        .collect()
}

/// A square sparse matrix in compressed-row form.
struct Csr {
    row_start: Vec<usize>,
    col: Vec<usize>,
    val: Vec<f64>,
}

impl Csr {
    /// Sum duplicate entries of `(row, col, value)` triplets.
    fn from_triplets(n: usize, mut t: Vec<(usize, usize, f64)>) -> Csr {
        t.sort_unstable_by_key(|&(r, c, _)| (r, c));
        let mut row_start = vec![0; n + 1];
        let mut col = Vec::with_capacity(t.len() / 4);
        let mut val: Vec<f64> = Vec::with_capacity(t.len() / 4);
        let mut last = None;
        for (r, c, v) in t {
            if last == Some((r, c)) {
                *val.last_mut().expect("an entry was pushed") += v;
            } else {
                col.push(c);
                val.push(v);
                row_start[r + 1] = col.len();
                last = Some((r, c));
            }
        }
        for r in 0..n {
            row_start[r + 1] = row_start[r + 1].max(row_start[r]);
        }
        Csr {
            row_start,
            col,
            val,
        }
    }

    fn mul(&self, x: &[f64], y: &mut [f64]) {
        for (r, out) in y.iter_mut().enumerate() {
            let mut s = 0.0;
            for k in self.row_start[r]..self.row_start[r + 1] {
                s += self.val[k] * x[self.col[k]];
            }
            *out = s;
        }
    }

    fn diagonal(&self) -> Vec<f64> {
        (0..self.row_start.len() - 1)
            .map(|r| {
                (self.row_start[r]..self.row_start[r + 1])
                    .find(|&k| self.col[k] == r)
                    .map_or(1.0, |k| self.val[k])
            })
            .collect()
    }

    /// Jacobi-preconditioned conjugate gradients from zero, until `‖r‖ ≤ tol ‖b‖` or
    /// `max_iter` iterations (then the iterate as it is: the caller's errors show it).
    fn pcg(&self, b: &[f64], tol: f64, max_iter: usize) -> (Vec<f64>, usize) {
        let n = b.len();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let inv_d: Vec<f64> = self.diagonal().iter().map(|d| 1.0 / d).collect();
        let mut x = vec![0.0; n];
        let mut r = b.to_vec();
        let mut z: Vec<f64> = r.iter().zip(&inv_d).map(|(r, d)| r * d).collect();
        let mut p = z.clone();
        let mut ap = vec![0.0; n];
        let mut rz = dot(&r, &z);
        let bnorm = dot(b, b).sqrt();
        if bnorm == 0.0 {
            return (x, 0);
        }
        for it in 0..max_iter {
            if dot(&r, &r).sqrt() <= tol * bnorm {
                return (x, it);
            }
            self.mul(&p, &mut ap);
            let alpha = rz / dot(&p, &ap);
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            for i in 0..n {
                z[i] = r[i] * inv_d[i];
            }
            let rz_new = dot(&r, &z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                p[i] = z[i] + beta * p[i];
            }
        }
        (x, max_iter)
    }
}
