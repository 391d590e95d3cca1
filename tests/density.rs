//! The crossing-density refusal judges what is painted: a soup of opaque
//! strokes whose outlines cross mostly inside the strokes' union is meshed
//! (the outlines a shape painted above covers are trimmed first), while a
//! soup whose painted outlines cross densely is refused with one line naming
//! a feature envelope at which it meshes.

use triwild::{Length, LoadOptions, Params, RegionMode, RegionOptions, Stage};
use triwild::{load_bytes, mesh_drawing};

/// `n` random segments (a fixed LCG) in a 100 × 100 viewBox, stroked black,
/// width 1, with `extra` attributes.
fn soup(n: usize, extra: &str) -> String {
    let mut x: u64 = 5;
    let mut next = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 * 100.0
    };
    let mut svg = String::from(r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">"#);
    for _ in 0..n {
        let (a, b, c, d) = (next(), next(), next(), next());
        svg.push_str(&format!(
            r##"<line x1="{a}" y1="{b}" x2="{c}" y2="{d}" stroke="#000" stroke-width="1"{extra}/>"##
        ));
    }
    svg.push_str("</svg>");
    svg
}

/// The BSP mesh of `svg` with μ = `mu`, regions left out (the density is
/// judged when the BSP starts).
fn bsp(svg: &str, mu: Length) -> triwild::Result<triwild::Meshed> {
    let d = load_bytes(svg.as_bytes(), &LoadOptions::DEFAULT).expect("the soup loads");
    let params = Params::DEFAULT
        .with_mu(mu)
        .with_stop_after(Some(Stage::Bsp));
    mesh_drawing(
        &d,
        &params,
        &RegionOptions::DEFAULT.with_mode(RegionMode::None),
    )
}

/// 500 opaque strokes about 2.6 deep: their outlines as drawn cross about
/// 2.6 times per μ (at μ = 0.005·d; refused when every outline was counted),
/// but each stroke is painted over by the later ones, and what is left of the
/// outlines crosses or ends on another far less often.
#[test]
fn a_soup_painted_over_itself_is_meshed() {
    let meshed = bsp(&soup(500, ""), Length::Rel(0.005)).expect("not refused");
    let counts = meshed.report.features.expect("feature counts");
    assert!(counts.cover_cuts > 1000, "{counts:?}");
    assert!(counts.trimmed_pieces > 10_000, "{counts:?}");
}

/// The same soup at 80 % stroke opacity: nothing paints over an outline, so
/// every crossing is painted and the soup is refused, in one line naming the
/// `--mu-abs` at which it passes; at that μ it is meshed.
#[test]
fn a_soup_painted_through_is_refused_naming_a_mu_that_passes() {
    let svg = soup(500, r#" stroke-opacity="0.8""#);
    let err = bsp(&svg, Length::Rel(0.005)).expect_err("refused");
    let msg = err.to_string();
    assert!(!msg.contains('\n'), "{msg}");
    assert!(msg.contains("cross one another"), "{msg}");
    let mu: f64 = msg
        .split("--mu-abs ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no --mu-abs value in: {msg}"));
    bsp(&svg, Length::Abs(mu)).expect("meshed at the μ the refusal names");
}
