//! A uniform grid of bounding boxes: the broad phase of the μ-separation test, so it never
//! compares all pairs (and of the size field's seeds' distance to the features,
//! `sizing::seeds`).

use kurbo::Rect;

/// Items (by `u32` id) bucketed by the grid cells their boxes overlap.
#[derive(Clone, Debug)]
pub(crate) struct Grid {
    x0: f64,
    y0: f64,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
    /// Each item's box, by id (what a query tests before it reports an item).
    boxes: Vec<Rect>,
}

impl Grid {
    /// A grid over `bounds` with cells of about `cell` (enlarged so that there are at most
    /// `4·expected_items + 16` cells, and at least a positive size).
    pub(crate) fn new(bounds: Rect, cell: f64, expected_items: usize) -> Grid {
        let (w, h) = (bounds.width().max(0.0), bounds.height().max(0.0));
        let max_cells = 4.0 * expected_items as f64 + 16.0;
        let mut cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            1.0
        };
        // Area bound, and a per-axis bound (a long thin drawing).
        cell = cell
            .max((w * h / max_cells).sqrt())
            .max(w.max(h) / max_cells);
        if !(cell.is_finite() && cell > 0.0) {
            cell = 1.0;
        }
        let nx = ((w / cell).floor() as usize)
            .saturating_add(1)
            .min(max_cells as usize);
        let ny = ((h / cell).floor() as usize)
            .saturating_add(1)
            .min(max_cells as usize);
        Grid {
            x0: bounds.x0,
            y0: bounds.y0,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
            boxes: Vec::new(),
        }
    }

    /// The side of a cell.
    pub(super) fn cell(&self) -> f64 {
        self.cell
    }

    fn span(&self, r: Rect) -> (usize, usize, usize, usize) {
        let ix = |x: f64, n: usize| (((x / self.cell).floor()).max(0.0) as usize).min(n - 1);
        (
            ix(r.x0 - self.x0, self.nx),
            ix(r.x1 - self.x0, self.nx),
            ix(r.y0 - self.y0, self.ny),
            ix(r.y1 - self.y0, self.ny),
        )
    }

    /// Add item `id` with box `r` (once per id).
    pub(crate) fn insert(&mut self, id: u32, r: Rect) {
        let (x0, x1, y0, y1) = self.span(r);
        for y in y0..=y1 {
            for x in x0..=x1 {
                self.cells[y * self.nx + x].push(id);
            }
        }
        let k = id as usize;
        if self.boxes.len() <= k {
            self.boxes.resize(k + 1, Rect::ZERO);
        }
        self.boxes[k] = r;
    }

    /// Calls `f` on every item whose box overlaps `r` (touching counts), each
    /// once, in no particular order, until `f` returns true; returns whether it did.
    ///
    /// An item is reported only from the cell holding the lower-left corner of its
    /// box's intersection with `r` (a cell both spans share), so no item is seen
    /// twice and nothing is sorted: the work is the items in the cells `r` covers.
    pub(crate) fn any(&self, r: Rect, f: impl FnMut(u32) -> bool) -> bool {
        self.any_of(r, |_| true, f)
    }

    /// [`Grid::any`] over the items `keep` accepts (asked first, before the
    /// item's box is looked at: a cheap filter saves the overlap tests).
    pub(super) fn any_of(
        &self,
        r: Rect,
        keep: impl Fn(u32) -> bool,
        mut f: impl FnMut(u32) -> bool,
    ) -> bool {
        let (x0, x1, y0, y1) = self.span(r);
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &id in &self.cells[y * self.nx + x] {
                    if !keep(id) {
                        continue;
                    }
                    let b = self.boxes[id as usize];
                    if b.x0 > r.x1 || b.x1 < r.x0 || b.y0 > r.y1 || b.y1 < r.y0 {
                        continue;
                    }
                    let (cx, _, cy, _) = self.span(Rect::new(
                        b.x0.max(r.x0),
                        b.y0.max(r.y0),
                        b.x1.min(r.x1),
                        b.y1.min(r.y1),
                    ));
                    if (cx, cy) == (x, y) && f(id) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// Every item whose box overlaps `r` (touching counts), each once, in
    /// increasing id order.
    pub(super) fn query(&self, r: Rect) -> Vec<u32> {
        let mut out = Vec::new();
        self.any(r, |id| {
            out.push(id);
            false
        });
        out.sort_unstable();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_overlapping_boxes_and_not_far_ones() {
        let mut g = Grid::new(Rect::new(0.0, 0.0, 100.0, 100.0), 1.0, 3);
        g.insert(0, Rect::new(0.0, 0.0, 1.0, 1.0));
        g.insert(1, Rect::new(50.0, 50.0, 99.0, 51.0));
        g.insert(2, Rect::new(98.0, 98.0, 100.0, 100.0));
        assert_eq!(g.query(Rect::new(0.5, 0.5, 2.0, 2.0)), vec![0]);
        assert_eq!(g.query(Rect::new(60.0, 49.0, 61.0, 50.5)), vec![1]);
        assert!(g.query(Rect::new(-10.0, 200.0, -5.0, 300.0)).is_empty());
        assert_eq!(g.query(Rect::new(0.0, 0.0, 100.0, 100.0)), vec![0, 1, 2]);
    }

    /// A fixed-seed generator of numbers in [0, 1).
    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut x = seed;
        move || {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn query_is_exactly_the_overlapping_boxes_once_each() {
        let mut r = rng(7);
        for (n, size) in [(50, 0.3), (400, 0.05), (400, 3.0), (1000, 0.001)] {
            let mut boxes = Vec::new();
            for _ in 0..n {
                // thin and tall, wide and flat, or square
                let (w, h) = match boxes.len() % 3 {
                    0 => (size * r(), size * r() * 0.01),
                    1 => (size * r() * 0.01, size * r()),
                    _ => (size * r(), size * r()),
                };
                let (x, y) = (10.0 * r() - 1.0, 10.0 * r() - 1.0);
                boxes.push(Rect::new(x, y, x + w, y + h));
            }
            let bounds = boxes.iter().fold(boxes[0], |a, b| a.union(*b));
            let mut g = Grid::new(bounds, size, n);
            for (i, b) in boxes.iter().enumerate() {
                g.insert(i as u32, *b);
            }
            for _ in 0..200 {
                let (x, y) = (12.0 * r() - 2.0, 12.0 * r() - 2.0);
                let q = Rect::new(x, y, x + size * 2.0 * r(), y + size * 2.0 * r());
                let expected: Vec<u32> = (0..n as u32)
                    .filter(|&i| boxes[i as usize].overlaps(q))
                    .collect();
                assert_eq!(g.query(q), expected, "{q:?}");
                let mut seen = 0;
                let found = g.any(q, |_| {
                    seen += 1;
                    false
                });
                assert!(!found);
                assert_eq!(seen, expected.len());
                if let Some(&first) = expected.first() {
                    let mut calls = 0;
                    assert!(g.any(q, |_| {
                        calls += 1;
                        true
                    }));
                    assert_eq!(calls, 1, "stops at the first hit ({first})");
                }
            }
        }
    }
}
