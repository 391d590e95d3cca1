//! Whole paths painted again on themselves merge at load.

use super::*;

fn doc(body: &str) -> String {
    format!(r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">{body}</svg>"#)
}

const BLOB: &str = "M30 30C40 20 60 20 70 30C80 40 80 60 70 70C60 80 40 80 30 70Z";

#[test]
fn a_path_painted_3000_times_loads_as_one_shape() {
    let body: String = (0..3000)
        .map(|_| format!(r##"<path fill="#336699" d="{BLOB}"/>"##))
        .collect();
    let d = load_bytes(doc(&body).as_bytes(), &LoadOptions::DEFAULT).expect("loads");
    assert_eq!(d.shapes.len(), 1);
    assert_eq!(d.paint.duplicates_merged, 2999);
    assert_eq!(d.features.len(), 4);
    assert_eq!(d.shapes[0].element_index, 2999);
}

#[test]
fn the_topmost_copy_keeps_its_colour_and_other_paths_stay() {
    let body = format!(
        r##"<path id="under" fill="#ff0000" d="{BLOB}"/>
        <rect x="0" y="0" width="50" height="50" fill="#00ff00"/>
        <path id="over" fill="#0000ff" d="{BLOB}"/>
        <path id="evenodd" fill="#0000ff" fill-rule="evenodd" d="{BLOB}"/>
        <path id="moved" fill="#0000ff" d="M30 30.001C40 20 60 20 70 30C80 40 80 60 70 70C60 80 40 80 30 70Z"/>"##
    );
    let d = load_bytes(doc(&body).as_bytes(), &LoadOptions::DEFAULT).expect("loads");
    let names: Vec<String> = d.shapes.iter().map(Shape::name).collect();
    // `under` is covered by `over`; the rect between them, the copy with
    // another rule and the moved copy stay.
    assert_eq!(names, ["shape-1", "over", "evenodd", "moved"]);
    assert_eq!(d.paint.duplicates_merged, 1);
    assert_eq!(d.shapes[1].fill_colour, Some([0, 0, 255]));
}

#[test]
fn stroke_centre_lines_painted_twice_merge() {
    let body = r##"<path fill="none" stroke="#000" stroke-width="0.001" d="M10 10C30 0 60 20 90 10"/>
        <path fill="none" stroke="#000" stroke-width="0.001" d="M10 10C30 0 60 20 90 10"/>"##;
    let d = load_bytes(doc(body).as_bytes(), &LoadOptions::DEFAULT).expect("loads");
    assert_eq!(d.shapes.len(), 1);
    assert_eq!(d.features.len(), 1);
    assert_eq!(d.paint.duplicates_merged, 1);
}
