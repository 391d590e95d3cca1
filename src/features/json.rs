//! The [`FeatureSet`] as JSON (format documented in `docs/features-json.md`).

use super::{FeatureSet, Parent, SectionId};
use kurbo::{CubicBez, Point};
use serde_json::{Value, json};

fn pt(p: Point) -> Value {
    json!([p.x, p.y])
}

fn ctrl(c: &CubicBez) -> Value {
    json!([pt(c.p0), pt(c.p1), pt(c.p2), pt(c.p3)])
}

/// The feature set as a JSON value: `d`, `params`, `counts`, `timing_ms`, `points`,
/// `point_sources`, `primary` and `secondary` (see `docs/features-json.md`). Coordinates
/// are output coordinates (y flipped).
pub(crate) fn to_json(fs: &FeatureSet) -> Value {
    let p = &fs.params;
    let primary: Vec<Value> = fs
        .primary
        .iter()
        .map(|s| {
            let parent = match s.parent {
                Parent::Cubic(c) => json!({"kind": "cubic", "ctrl": ctrl(&c)}),
                Parent::Line(l) => json!({"kind": "line", "ctrl": [pt(l.p0), pt(l.p1)]}),
                Parent::Conic(c) => json!({
                    "kind": "conic",
                    "ctrl": [pt(c.p0), pt(c.p1), pt(c.p2)],
                    "w": c.w,
                }),
            };
            json!({
                "ctrl": ctrl(&s.ctrl),
                "t": s.t,
                "source": s.source,
                "parent": parent,
                "prev": s.prev.map(SectionId::index),
                "next": s.next.map(SectionId::index),
            })
        })
        .collect();
    let secondary: Vec<Value> = fs
        .secondary
        .iter()
        .map(|s| {
            json!({
                "points": s.points.iter().map(|p| pt(*p)).collect::<Vec<_>>(),
                "source": s.source,
            })
        })
        .collect();
    json!({
        "d": p.d,
        "params": {
            "mu": p.mu,
            "eps": p.eps,
            "eps_m": p.eps_m,
            "l": p.l,
            "l_min": p.l_min,
            "alpha_deg": p.alpha.to_degrees(),
        },
        "counts": fs.counts,
        "timing_ms": fs.timing,
        "points": fs.points.iter().map(|p| pt(p.pos)).collect::<Vec<_>>(),
        "point_sources": fs.points.iter().map(|p| p.source).collect::<Vec<_>>(),
        "primary": primary,
        "secondary": secondary,
    })
}
