//! The output frame: from usvg's absolute coordinates (CSS px of the root
//! viewport, y down) to output coordinates ([`Units`], `scale`, y up).
//!
//! usvg folds the root `viewBox` → `width`/`height` mapping into the root group,
//! so every path's absolute transform starts with it. In [`Units::User`] that
//! mapping is recomputed here exactly as usvg 0.49 computes it (`ViewBox::
//! to_transform` on the tree's size, in f32 from the same parsed attributes),
//! and undone in f64: for a path directly under the root, the absolute
//! transform's factors divided by the mapping's are exactly the document's.

use crate::units::Units;
use crate::{Error, Result};
use kurbo::Affine;
use usvg::roxmltree;

/// The root `viewBox` and `preserveAspectRatio` attributes, parsed as usvg parses them.
#[derive(Clone, Copy, Debug)]
pub(super) struct RootViewBox {
    /// The `viewBox` rectangle (f32, as usvg keeps it).
    rect: usvg::NonZeroRect,
    /// `preserveAspectRatio` (default `xMidYMid meet`).
    aspect: svgtypes::AspectRatio,
    /// The `viewBox` `[x, y, w, h]` as the document writes it, in f64.
    exact: [f64; 4],
}

impl RootViewBox {
    /// The root element's `viewBox`, if it has a valid one (positive, finite
    /// size); usvg ignores any other and so do we.
    pub(super) fn of(root: roxmltree::Node<'_, '_>) -> Option<RootViewBox> {
        let vb: svgtypes::ViewBox = root.attribute("viewBox")?.parse().ok()?;
        #[allow(
            clippy::cast_possible_truncation,
            reason = "usvg keeps the viewBox in f32; the mapping must be usvg's"
        )]
        let rect =
            usvg::NonZeroRect::from_xywh(vb.x as f32, vb.y as f32, vb.w as f32, vb.h as f32)?;
        let aspect = root
            .attribute("preserveAspectRatio")
            .and_then(|s| s.parse().ok())
            .unwrap_or_default();
        Some(RootViewBox {
            rect,
            aspect,
            exact: [vb.x, vb.y, vb.w, vb.h],
        })
    }

    /// The `viewBox` rectangle in output coordinates (y up): in user units its
    /// own numbers times `scale`, in px its image under the viewport mapping.
    pub(super) fn output_rect(&self, units: Units, scale: f64, size: usvg::Size) -> kurbo::Rect {
        let [x, y, w, h] = self.exact;
        let (x0, y0, x1, y1) = match units {
            Units::User => (x, y, x + w, y + h),
            Units::Px => {
                let (sx, sy, tx, ty) = self.mapping(size);
                let [sx, sy, tx, ty] = [sx, sy, tx, ty].map(f64::from);
                (
                    sx * x + tx,
                    sy * y + ty,
                    sx * (x + w) + tx,
                    sy * (y + h) + ty,
                )
            }
        };
        // (+ 0.0: a side at y = 0 is 0, not -0)
        kurbo::Rect::new(
            x0 * scale + 0.0,
            -y1 * scale + 0.0,
            x1 * scale + 0.0,
            -y0 * scale + 0.0,
        )
    }

    /// The viewBox → viewport mapping for a viewport of `size` px, as
    /// `(sx, sy, tx, ty)`: `x_px = sx·x_user + tx` (usvg's `ViewBox::to_transform`,
    /// the same f32 operations in the same order, so the result is bit-identical).
    fn mapping(&self, size: usvg::Size) -> (f32, f32, f32, f32) {
        let vr = self.rect;
        fit(
            [vr.x(), vr.y(), vr.width(), vr.height()],
            self.aspect,
            size.width(),
            size.height(),
        )
    }
}

/// SVG's `viewBox` → viewport mapping for a viewBox `[x, y, w, h]` shown in a
/// `width` × `height` viewport, as `(sx, sy, tx, ty)`: `x_vp = sx·x + tx` (usvg's
/// `ViewBox::to_transform`: the same operations in the same order, so in f32 the
/// result is usvg's bit for bit; in f64 it is the document's mapping).
pub(super) fn fit<T>(vb: [T; 4], aspect: svgtypes::AspectRatio, width: T, height: T) -> (T, T, T, T)
where
    T: Copy
        + PartialOrd
        + From<u8>
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<Output = T>
        + std::ops::Div<Output = T>
        + std::ops::Neg<Output = T>,
{
    use svgtypes::Align;
    let [x0, y0, vw, vh] = vb;
    let sx = width / vw;
    let sy = height / vh;
    let (sx, sy) = if aspect.align == Align::None {
        (sx, sy)
    } else {
        // meet: the whole viewBox is visible (smaller factor); slice: it covers
        // the viewport (larger factor)
        let s = if aspect.slice == (sx > sy) { sx } else { sy };
        (s, s)
    };
    let x = -x0 * sx;
    let y = -y0 * sy;
    let w = width - vw * sx;
    let h = height - vh * sy;
    let two = T::from(2u8);
    let (tx, ty) = match aspect.align {
        Align::None | Align::XMinYMin => (x, y),
        Align::XMidYMin => (x + w / two, y),
        Align::XMaxYMin => (x + w, y),
        Align::XMinYMid => (x, y + h / two),
        Align::XMidYMid => (x + w / two, y + h / two),
        Align::XMaxYMid => (x + w, y + h / two),
        Align::XMinYMax => (x, y + h),
        Align::XMidYMax => (x + w / two, y + h),
        Align::XMaxYMax => (x + w, y + h),
    };
    (sx, sy, tx, ty)
}

/// A scale must be finite and positive.
///
/// # Errors
/// [`Error::InvalidParams`] otherwise.
pub(super) fn check_scale(scale: f64) -> Result<()> {
    if scale.is_finite() && scale > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParams(format!(
            "--scale must be a positive finite number, got {scale}"
        )))
    }
}

/// What happens to usvg's absolute coordinates on the way out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Frame {
    /// The root viewport mapping to undo, `(sx, sy, tx, ty)` in f64; `None` in
    /// px, or when it is the identity (no `viewBox`, or one equal to the size).
    undo: Option<[f64; 4]>,
    /// Multiplies every output coordinate (1 leaves them untouched).
    scale: f64,
    /// Applied to usvg's absolute transforms first (in usvg's coordinates):
    /// the transforms usvg was kept from below an element (see
    /// [`Frame::with_omitted`]); `None` everywhere else.
    omitted: Option<Affine>,
}

impl Frame {
    /// The frame for `units` and `scale`, for a tree of `size` px whose root
    /// element had `view_box`.
    ///
    /// # Errors
    /// [`Error::InvalidParams`] for a `scale` that is not finite and positive;
    /// [`Error::BadCoordinate`] in user units when the root viewport mapping cannot
    /// be undone (a factor that is zero or not finite in f32).
    pub(super) fn new(
        units: Units,
        scale: f64,
        view_box: Option<RootViewBox>,
        size: usvg::Size,
    ) -> Result<Frame> {
        check_scale(scale)?;
        let undo = match (units, view_box) {
            (Units::Px, _) | (Units::User, None) => None,
            (Units::User, Some(vb)) => {
                let (sx, sy, tx, ty) = vb.mapping(size);
                let m = [sx, sy, tx, ty].map(f64::from);
                if !(m.iter().all(|v| v.is_finite()) && m[0] > 0.0 && m[1] > 0.0) {
                    return Err(Error::BadCoordinate(format!(
                        "the root viewBox {} {} {} {} cannot be mapped to the {} × {} px \
                         viewport and back (try --units px)",
                        vb.rect.x(),
                        vb.rect.y(),
                        vb.rect.width(),
                        vb.rect.height(),
                        size.width(),
                        size.height()
                    )));
                }
                (m != [1.0, 1.0, 0.0, 0.0]).then_some(m)
            }
        };
        Ok(Frame {
            undo,
            scale,
            omitted: None,
        })
    }

    /// The frame below an element whose own transform `t` usvg did not apply
    /// (its content in usvg's tree lies in the element's own coordinates):
    /// `parent` is usvg's absolute transform of the element's parent, so the
    /// content's true absolute transform is `parent · t · parent⁻¹` times
    /// usvg's. `None` when `parent` cannot be inverted.
    pub(super) fn with_omitted(&self, parent: usvg::Transform, t: Affine) -> Option<Frame> {
        let p = affine(parent);
        let det = p.determinant();
        (det.is_finite() && det != 0.0).then(|| {
            let fix = p * t * p.inverse();
            Frame {
                omitted: Some(self.omitted.map_or(fix, |o| o * fix)),
                ..*self
            }
        })
    }

    /// The affine map `[sx, ky, kx, sy, tx, ty]` from a path's own coordinates to
    /// output coordinates before the y flip, given the path's absolute transform
    /// (usvg's order: `x' = sx·x + kx·y + tx`, `y' = ky·x + sy·y + ty`).
    pub(super) fn map(&self, abs: usvg::Transform) -> [f64; 6] {
        let [mut sx, mut ky, mut kx, mut sy, mut tx, mut ty] = match self.omitted {
            None => [abs.sx, abs.ky, abs.kx, abs.sy, abs.tx, abs.ty].map(f64::from),
            Some(o) => (o * affine(abs)).as_coeffs(),
        };
        if let Some([vsx, vsy, vtx, vty]) = self.undo {
            // (x_px − vtx) / vsx, row by row: divisions, so that a factor equal
            // to the mapping's gives exactly 1
            sx /= vsx;
            kx /= vsx;
            tx = (tx - vtx) / vsx;
            ky /= vsy;
            sy /= vsy;
            ty = (ty - vty) / vsy;
        }
        let m = [sx, ky, kx, sy, tx, ty];
        if self.scale == 1.0 {
            m
        } else {
            m.map(|v| v * self.scale)
        }
    }
}

/// A usvg transform as a kurbo affine map, in f64.
fn affine(t: usvg::Transform) -> Affine {
    Affine::new([t.sx, t.ky, t.kx, t.sy, t.tx, t.ty].map(f64::from))
}
