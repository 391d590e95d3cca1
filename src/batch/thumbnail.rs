//! Thumbnails of the meshes for the report page's gallery: each file's SVG
//! preview (written by its batch child with `--preview`) rendered small with
//! resvg, the renderer that goes with usvg, and encoded as PNG.
//!
//! Guarantees: [`render_png`] never panics on a missing, empty or broken
//! preview (it returns `None`), and the same preview always gives the same
//! bytes (the page is reproducible).

use resvg::{tiny_skia, usvg};
use std::path::Path;

/// The longer side of a thumbnail, pixels.
pub const THUMB_PX: u32 = 128;

/// The preview at `path` rendered to fit in `px` × `px` pixels, as PNG bytes;
/// `None` if the file is missing or not an SVG resvg can draw.
pub fn render_png(path: &Path, px: u32) -> Option<Vec<u8>> {
    let data = std::fs::read(path).ok()?;
    render_svg_png(&data, px)
}

/// [`render_png`] on the SVG text itself.
pub(crate) fn render_svg_png(svg: &[u8], px: u32) -> Option<Vec<u8>> {
    let tree = usvg::Tree::from_data(svg, &usvg::Options::default()).ok()?;
    let size = tree.size();
    let (w, h) = (f64::from(size.width()), f64::from(size.height()));
    if !(w > 0.0 && h > 0.0 && w.is_finite() && h.is_finite()) {
        return None;
    }
    let scale = f64::from(px.max(1)) / w.max(h);
    let pw = ((w * scale).round() as u32).clamp(1, px.max(1));
    let ph = ((h * scale).round() as u32).clamp(1, px.max(1));
    let mut pixmap = tiny_skia::Pixmap::new(pw, ph)?;
    pixmap.fill(tiny_skia::Color::WHITE);
    let s = scale as f32;
    resvg::render(
        &tree,
        tiny_skia::Transform::from_scale(s, s),
        &mut pixmap.as_mut(),
    );
    indexed_png(pixmap.width(), pixmap.height(), pixmap.data())
}

/// Colours a thumbnail keeps: its most frequent ones; the rest (the
/// anti-aliased edges) take the nearest of them.
const PALETTE: usize = 16;

/// Opaque RGBA pixels as an 8-bit palette PNG (a fifth of the size of RGBA
/// for a mesh drawing: flat fills keep their exact colours).
fn indexed_png(w: u32, h: u32, rgba: &[u8]) -> Option<Vec<u8>> {
    let px: Vec<[u8; 3]> = rgba.chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect();
    let mut freq: std::collections::HashMap<[u8; 3], usize> = Default::default();
    for p in &px {
        *freq.entry(*p).or_default() += 1;
    }
    let mut colours: Vec<([u8; 3], usize)> = freq.into_iter().collect();
    // most frequent first, ties by colour: the same picture, the same palette
    colours.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    colours.truncate(PALETTE);
    let palette: Vec<[u8; 3]> = colours.iter().map(|c| c.0).collect();
    let mut memo: std::collections::HashMap<[u8; 3], u8> = palette
        .iter()
        .enumerate()
        .map(|(i, c)| (*c, i as u8))
        .collect();
    let index: Vec<u8> = px
        .iter()
        .map(|p| {
            *memo.entry(*p).or_insert_with(|| {
                let d = |c: &[u8; 3]| -> i32 {
                    (0..3)
                        .map(|k| (i32::from(c[k]) - i32::from(p[k])).pow(2))
                        .sum()
                };
                (0..palette.len())
                    .min_by_key(|&i| d(&palette[i]))
                    .unwrap_or(0) as u8
            })
        })
        .collect();
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Indexed);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_palette(palette.concat());
        enc.set_compression(png::Compression::High);
        let mut writer = enc.write_header().ok()?;
        writer.write_image_data(&index).ok()?;
        writer.finish().ok()?;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_small_and_refuses_garbage() {
        let svg = br#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 200 100" width="1000" height="500">
            <rect x="0" y="0" width="100" height="100" fill="red"/></svg>"#;
        let png = render_svg_png(svg, 64).expect("renders");
        assert_eq!(&png[1..4], b"PNG");
        // width and height of the IHDR chunk: 64 x 32
        let be = |i: usize| u32::from_be_bytes([png[i], png[i + 1], png[i + 2], png[i + 3]]);
        assert_eq!((be(16), be(20)), (64, 32));
        assert_eq!(render_svg_png(svg, 64), Some(png), "reproducible");
        assert!(render_svg_png(b"", 64).is_none());
        assert!(render_svg_png(b"not svg <", 64).is_none());
        assert!(render_png(Path::new("/nonexistent/preview.svg"), 64).is_none());
    }
}
