//! A uniform grid of bounding boxes: the broad phase of the μ-separation test, so it never
//! compares all pairs.

use kurbo::Rect;

/// Items (by `u32` id) bucketed by the grid cells their boxes overlap.
#[derive(Clone, Debug)]
pub(super) struct Grid {
    x0: f64,
    y0: f64,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl Grid {
    /// A grid over `bounds` with cells of about `cell` (enlarged so that there are at most
    /// `4·expected_items + 16` cells, and at least a positive size).
    pub(super) fn new(bounds: Rect, cell: f64, expected_items: usize) -> Grid {
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
        let nx = ((w / cell).floor() as usize + 1).min(max_cells as usize);
        let ny = ((h / cell).floor() as usize + 1).min(max_cells as usize);
        Grid {
            x0: bounds.x0,
            y0: bounds.y0,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        }
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

    /// Add item `id` with box `r`.
    pub(super) fn insert(&mut self, id: u32, r: Rect) {
        let (x0, x1, y0, y1) = self.span(r);
        for y in y0..=y1 {
            for x in x0..=x1 {
                self.cells[y * self.nx + x].push(id);
            }
        }
    }

    /// Every item whose box may overlap `r`, each once, in increasing id order.
    pub(super) fn query(&self, r: Rect) -> Vec<u32> {
        let (x0, x1, y0, y1) = self.span(r);
        let mut out = Vec::new();
        for y in y0..=y1 {
            for x in x0..=x1 {
                out.extend_from_slice(&self.cells[y * self.nx + x]);
            }
        }
        out.sort_unstable();
        out.dedup();
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
        assert!(g.query(Rect::new(-10.0, 200.0, -5.0, 300.0)).len() <= 3);
        assert_eq!(g.query(Rect::new(0.0, 0.0, 100.0, 100.0)), vec![0, 1, 2]);
    }
}
