//! The exact geometric kernel: the only module that does rational arithmetic.
//!
//! It owns the rational point type [`PointQ`], the orientation predicate
//! ([`orient2d`] for `f64` points, [`orient2d_q`] for rational points, both
//! returning an [`Orientation`]), exact line/segment intersections
//! ([`line_intersection`](intersect::line_intersection), [`segment_intersection`]) and the
//! barycentre of a convex polygon ([`PointQ::barycentre`]), and two tolerance
//! tests decided exactly ([`near_line`], [`within`]: is a point within a distance
//! of a line, of another point).
//!
//! Guarantees: every answer is exact. Predicates run a float filter first
//! whose error bound is proven (outward-rounded interval arithmetic over
//! enclosures of the rational coordinates, or Shewchuk's adaptive predicate
//! from the `robust` crate for `f64` points) and fall back to rationals when
//! the filter cannot decide. Constructions (intersections, barycentres) are
//! exact rationals; [`PointQ::to_f64`] rounds to the nearest `f64` and says
//! whether the rounding was exact.
//!
//! docs/design.md "Exactness"; thesis §2.3.1 (operations closed under rationals) and
//! §2.3.4 (hybrid kernel).
#![allow(
    clippy::disallowed_types,
    reason = "the exact kernel is the one module allowed to use rug rationals (STYLE: the exact kernel)"
)]

mod intersect;
pub(crate) mod predicates;
pub(crate) mod rational;

pub(crate) use intersect::{SegmentIntersection, line_intersection_f64, segment_intersection};
pub(crate) use predicates::{
    Orientation, PointRef, near_line, orient2d, orient2d_mixed, orient2d_q, within,
};
pub(crate) use rational::PointQ;
