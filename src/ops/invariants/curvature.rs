//! Invariant 3: the curve piece of a primary edge turns less than α
//! (docs/design.md "Invariants" 3, Theorem 4.4).
//!
//! A section has constant-sign curvature (the feature stage splits at
//! inflections), so the turn of a piece is the angle between the end tangents
//! of its control polygon, the measure the feature stage bounds. An edge's
//! piece lies on a chain of sections, though, and may span an inflection
//! between them: its turn is then the sum of its parts' between the
//! inflections (an S-shaped piece whose end tangents are parallel turns as
//! much as its two bends together, not 0), and a piece across a cusp fails.
//! For a conic
//! parent the control polygon is its hull ([`Parent::restrict`]), which has the
//! conic's own end tangents, so the turn is the conic's exactly.
//!
//! [`Parent::restrict`]: crate::features::Parent::restrict

use super::super::Context;
use crate::mesh::angle_between;
use kurbo::CubicBez;

/// Angle (radians, in `[0, π]`) between the end tangents of a cubic control
/// polygon (a cubic piece, or a conic piece's hull); π when a tangent cannot be
/// found.
pub(crate) fn turn(c: &CubicBez) -> f64 {
    let tangent = |a: kurbo::Point, b: kurbo::Point, d: kurbo::Point| {
        let t = b - a;
        if t.hypot2() > 0.0 { t } else { d - a }
    };
    let u = tangent(c.p0, c.p1, c.p2);
    let v = {
        let t = c.p3 - c.p2;
        if t.hypot2() > 0.0 { t } else { c.p3 - c.p1 }
    };
    if u.hypot2() == 0.0 || v.hypot2() == 0.0 {
        return std::f64::consts::PI;
    }
    angle_between(u, v)
}

/// Whether the piece `[t0, t1]` (either order) of `section` turns less than
/// `ctx.turn_bound()` (α, or the curved rule's bound in curved mode) and lies
/// inside the section's interval. An unknown section fails.
pub(crate) fn holds(ctx: &Context, section: u32, t: [f64; 2]) -> bool {
    let Some(s) = ctx.section(section) else {
        return false;
    };
    let (lo, hi) = (t[0].min(t[1]), t[0].max(t[1]));
    // Parameters interpolated along a chord may miss the ends by rounding.
    let slack = 1e-9 * (s.t[1] - s.t[0]).abs();
    if !(lo.is_finite() && hi.is_finite()) || lo < s.t[0] - slack || hi > s.t[1] + slack || lo == hi
    {
        return false;
    }
    if s.parent.is_line() {
        return true;
    }
    let Some(inflections) = s.parent.inflections_within(lo, hi) else {
        return false;
    };
    let mut total = 0.0;
    let mut from = lo;
    for to in inflections.into_iter().chain([hi]) {
        total += turn(&s.parent.restrict(from, to));
        from = to;
    }
    total < ctx.turn_bound()
}
