//! Scalar polynomials on a triangle in Bernstein form, degree 0 to 4.
//!
//! A degree-`n` polynomial over the triangle with barycentric coordinates
//! `(λ0, λ1, λ2)` is `Σ c_α B_α(λ)` with `B_α = n!/(α0! α1! α2!) λ0^α0 λ1^α1 λ2^α2`
//! over the multi-indices `|α| = n`. Its coefficients bound it (the `B_α` are
//! non-negative and sum to 1), the three corner coefficients are its values at the
//! corners, and the coefficients on a sub-triangle follow exactly from blossoming
//! (repeated de Casteljau steps), which is how [`BernsteinTri::split4`] refines the
//! bound. The Jacobian determinant of a Lagrange triangle (`element::jacobian`) is kept
//! in this form.
//!
//! Lattice order: `α = (n − j − k, j, k)` lies at index
//! `k (n + 1) − k (k − 1) / 2 + j`, i.e. rows of growing `k` (the power of `λ2`), each
//! row by growing `j` (the power of `λ1`). In reference coordinates `ξ = λ1`, `η = λ2`.

/// Largest degree a [`BernsteinTri`] holds (the determinant of a cubic map).
pub const MAX_DEGREE: usize = 4;

/// Number of coefficients of a degree-`n` triangle polynomial.
pub const fn len(n: usize) -> usize {
    (n + 1) * (n + 2) / 2
}

/// Index of the multi-index `(n − j − k, j, k)` in the lattice order.
pub const fn index(n: usize, j: usize, k: usize) -> usize {
    k * (n + 1) - k * k.saturating_sub(1) / 2 + j
}

/// The multi-indices `(α0, α1, α2)` of degree `n`, in lattice order.
pub fn lattice(n: usize) -> impl Iterator<Item = [usize; 3]> {
    (0..=n).flat_map(move |k| (0..=n - k).map(move |j| [n - j - k, j, k]))
}

/// `n! / (a! b! c!)` for `n ≤ 8` (as f64; exact).
#[cfg(test)]
pub(crate) fn multinomial(a: [usize; 3]) -> f64 {
    const FACT: [f64; 9] = [1.0, 1.0, 2.0, 6.0, 24.0, 120.0, 720.0, 5040.0, 40320.0];
    FACT[a[0] + a[1] + a[2]] / (FACT[a[0]] * FACT[a[1]] * FACT[a[2]])
}

/// A scalar polynomial of degree ≤ [`MAX_DEGREE`] on a triangle, in Bernstein form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BernsteinTri {
    degree: usize,
    coeffs: [f64; len(MAX_DEGREE)],
}

impl BernsteinTri {
    /// The polynomial with the given coefficients (lattice order).
    ///
    /// # Panics
    /// If `coeffs.len()` is not `len(n)` for some `n ≤ 4`.
    pub fn new(coeffs: &[f64]) -> BernsteinTri {
        let degree = (0..=MAX_DEGREE)
            .find(|&n| len(n) == coeffs.len())
            .expect("a Bernstein triangle has 1, 3, 6, 10 or 15 coefficients");
        let mut c = [0.0; len(MAX_DEGREE)];
        c[..coeffs.len()].copy_from_slice(coeffs);
        BernsteinTri { degree, coeffs: c }
    }

    /// The polynomial's degree.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The coefficients in lattice order.
    pub fn coeffs(&self) -> &[f64] {
        &self.coeffs[..len(self.degree)]
    }

    /// Smallest coefficient: a lower bound of the polynomial on the triangle.
    pub fn min_coeff(&self) -> f64 {
        self.coeffs().iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Largest coefficient: an upper bound of the polynomial on the triangle.
    pub fn max_coeff(&self) -> f64 {
        self.coeffs()
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// The values at the three corners (exact: they are coefficients).
    pub fn corner_values(&self) -> [f64; 3] {
        let n = self.degree;
        [
            self.coeffs[index(n, 0, 0)],
            self.coeffs[index(n, n, 0)],
            self.coeffs[index(n, 0, n)],
        ]
    }

    /// The mean value over the triangle (the mean of the coefficients: every
    /// Bernstein polynomial of degree n integrates to area / len(n)).
    pub fn mean(&self) -> f64 {
        self.coeffs().iter().sum::<f64>() / len(self.degree) as f64
    }

    /// Value at barycentric coordinates `lambda` (de Casteljau).
    pub fn eval(&self, lambda: [f64; 3]) -> f64 {
        let mut c = self.coeffs;
        for m in (1..=self.degree).rev() {
            step(&mut c, m, lambda);
        }
        c[0]
    }

    /// The same polynomial in Bernstein form over the sub-triangle whose corners
    /// have barycentric coordinates `corners` (blossoming: exact up to rounding).
    pub fn restrict(&self, corners: [[f64; 3]; 3]) -> BernsteinTri {
        let n = self.degree;
        let mut out = [0.0; len(MAX_DEGREE)];
        // Coefficient (a, b, c) of the sub-triangle is the blossom
        // f(u^a, v^b, w^c): a de Casteljau steps at u, b at v, c at w.
        let mut cu = self.coeffs;
        for a in 0..=n {
            if a > 0 {
                step(&mut cu, n - a + 1, corners[0]);
            }
            let mut cv = cu;
            for b in 0..=n - a {
                if b > 0 {
                    step(&mut cv, n - a - b + 1, corners[1]);
                }
                let mut cw = cv;
                for m in (1..=n - a - b).rev() {
                    step(&mut cw, m, corners[2]);
                }
                out[index(n, b, n - a - b)] = cw[0];
            }
        }
        BernsteinTri {
            degree: n,
            coeffs: out,
        }
    }

    /// The four sub-triangles of the midpoint split, as (restriction, corners in
    /// the parent's barycentric coordinates), counter-clockwise like the parent:
    /// the three corner triangles, then the middle one.
    pub fn split4(&self, parent: [[f64; 3]; 3]) -> [(BernsteinTri, [[f64; 3]; 3]); 4] {
        let mid = |a: [f64; 3], b: [f64; 3]| {
            [
                0.5 * (a[0] + b[0]),
                0.5 * (a[1] + b[1]),
                0.5 * (a[2] + b[2]),
            ]
        };
        let (v0, v1, v2) = (parent[0], parent[1], parent[2]);
        let (m01, m12, m20) = (mid(v0, v1), mid(v1, v2), mid(v2, v0));
        let global = [
            [v0, m01, m20],
            [m01, v1, m12],
            [m20, m12, v2],
            [m12, m20, m01],
        ];
        let n = self.degree;
        let tables = &SPLIT_TABLES[n];
        [0, 1, 2, 3].map(|i| {
            let mut c = [0.0; len(MAX_DEGREE)];
            for &(o, j, w) in &tables[i] {
                c[o as usize] += w * self.coeffs[j as usize];
            }
            (
                BernsteinTri {
                    degree: n,
                    coeffs: c,
                },
                global[i],
            )
        })
    }

    /// The same polynomial scaled by `s`.
    pub fn scaled(&self, s: f64) -> BernsteinTri {
        let mut out = *self;
        for c in &mut out.coeffs[..len(self.degree)] {
            *c *= s;
        }
        out
    }
}

/// Corners of the four midpoint-split children in their parent's barycentrics.
const CHILDREN: [[[f64; 3]; 3]; 4] = [
    [[1.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5]],
    [[0.5, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.5, 0.5]],
    [[0.5, 0.0, 0.5], [0.0, 0.5, 0.5], [0.0, 0.0, 1.0]],
    [[0.0, 0.5, 0.5], [0.5, 0.0, 0.5], [0.5, 0.5, 0.0]],
];

/// Sparse subdivision matrices of the midpoint split, per degree and child:
/// (child coefficient, parent coefficient, weight). Built once by blossoming the
/// unit polynomials; the weights are dyadic rationals, exact in f64.
type SplitTable = Vec<(u8, u8, f64)>;
static SPLIT_TABLES: std::sync::LazyLock<[[SplitTable; 4]; MAX_DEGREE + 1]> =
    std::sync::LazyLock::new(|| {
        std::array::from_fn(|n| {
            std::array::from_fn(|child| {
                let mut t = Vec::new();
                for j in 0..len(n) {
                    let mut unit = [0.0; len(MAX_DEGREE)];
                    unit[j] = 1.0;
                    let p = BernsteinTri {
                        degree: n,
                        coeffs: unit,
                    };
                    let r = p.restrict(CHILDREN[child]);
                    for (o, &w) in r.coeffs().iter().enumerate() {
                        if w != 0.0 {
                            t.push((o as u8, j as u8, w));
                        }
                    }
                }
                t.sort_by_key(|&(o, j, _)| (o, j));
                t
            })
        })
    });

/// One de Casteljau step from degree `m` to `m − 1` at barycentric point `p`, in place.
fn step(c: &mut [f64; len(MAX_DEGREE)], m: usize, p: [f64; 3]) {
    for k in 0..m {
        for j in 0..m - k {
            c[index(m - 1, j, k)] = p[0] * c[index(m, j, k)]
                + p[1] * c[index(m, j + 1, k)]
                + p[2] * c[index(m, j, k + 1)];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct evaluation from the definition.
    fn direct(p: &BernsteinTri, l: [f64; 3]) -> f64 {
        let n = p.degree();
        lattice(n)
            .zip(p.coeffs())
            .map(|(a, c)| {
                c * multinomial(a)
                    * l[0].powi(a[0] as i32)
                    * l[1].powi(a[1] as i32)
                    * l[2].powi(a[2] as i32)
            })
            .sum()
    }

    fn sample(n: usize) -> BernsteinTri {
        let c: Vec<f64> = (0..len(n))
            .map(|i| ((i * 7 + 3) % 11) as f64 - 4.5)
            .collect();
        BernsteinTri::new(&c)
    }

    #[test]
    fn index_matches_lattice() {
        for n in 0..=MAX_DEGREE {
            for (i, a) in lattice(n).enumerate() {
                assert_eq!(index(n, a[1], a[2]), i);
                assert_eq!(a[0] + a[1] + a[2], n);
            }
            assert_eq!(lattice(n).count(), len(n));
        }
    }

    #[test]
    fn de_casteljau_matches_definition() {
        for n in 0..=MAX_DEGREE {
            let p = sample(n);
            for l in [[0.2, 0.3, 0.5], [1.0, 0.0, 0.0], [0.0, 0.25, 0.75]] {
                assert!((p.eval(l) - direct(&p, l)).abs() < 1e-12);
            }
            let mean = p.mean();
            assert!(mean.is_finite());
        }
    }

    #[test]
    fn restriction_agrees_with_parent() {
        for n in 1..=MAX_DEGREE {
            let p = sample(n);
            for (child, corners) in p.split4([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]) {
                for l in [[0.2, 0.3, 0.5], [0.6, 0.1, 0.3], [1.0, 0.0, 0.0]] {
                    // the child's point l in the parent's barycentrics
                    let g: [f64; 3] = std::array::from_fn(|d| {
                        l[0] * corners[0][d] + l[1] * corners[1][d] + l[2] * corners[2][d]
                    });
                    assert!((child.eval(l) - p.eval(g)).abs() < 1e-12, "n {n}");
                }
            }
        }
    }

    #[test]
    fn split_tables_match_blossoming() {
        for n in 0..=MAX_DEGREE {
            let p = sample(n);
            let unit = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            for (i, (child, corners)) in p.split4(unit).into_iter().enumerate() {
                assert_eq!(corners, CHILDREN[i]);
                let direct = p.restrict(CHILDREN[i]);
                for (a, b) in child.coeffs().iter().zip(direct.coeffs()) {
                    assert!((a - b).abs() < 1e-13, "n {n} child {i}: {a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn mean_is_the_integral() {
        // ∫ λ1² over the reference triangle (area 1/2) is 1/12; mean = 1/6.
        let mut c = [0.0; 6];
        c[index(2, 2, 0)] = 1.0;
        assert!((BernsteinTri::new(&c).mean() - 1.0 / 6.0).abs() < 1e-15);
    }
}
