//! The README's own-groom timeline (its "Your own groom" section), verbatim:
//! it validates, bakes the swatch the section tells a reader to generate, and
//! its set shows (the released swatch leans where the pillow pressed it).

use crate::util::TestDir;

/// The first ```toml block after the README's "## Your own groom".
fn own_groom_timeline() -> String {
    let readme = include_str!("../../README.md");
    let section = readme
        .split("\n## Your own groom\n")
        .nth(1)
        .expect("README has a 'Your own groom' section");
    let block = section
        .split("```toml\n")
        .nth(1)
        .expect("the section has a toml block");
    block.split("\n```").next().unwrap().to_string()
}

#[test]
fn readme_own_groom_timeline_bakes_and_keeps_a_set() {
    let dir = TestDir::new();
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "my_groom.abc",
        "--strands",
        "100",
        "--length",
        "0.04",
        "--segment-length",
        "0.005",
    ]);
    std::fs::write(dir.path("my_bed_hair.toml"), own_groom_timeline()).unwrap();
    dir.run_ok(&["validate", "my_bed_hair.toml"]);
    dir.run_ok(&["bake", "my_bed_hair.toml", "-q"]);
    for file in [
        "my_bed_hair.abc",
        "my_bed_hair_rest.usda",
        "my_bed_hair_sheet.png",
    ] {
        assert!(dir.path("out").join(file).is_file(), "no out/{file}");
    }
    // The set: the rest shape's tips sit off to the side of the roots (the
    // pillow was tilted), by at least a few millimetres.
    let rest = importers::read(&dir.path("out/my_bed_hair_rest.usda")).unwrap();
    let mut offsets = Vec::new();
    let mut start = 0usize;
    for &count in &rest.strand_vertex_counts {
        let count = count as usize;
        let (root, tip) = (rest.points[start], rest.points[start + count - 1]);
        offsets.push((tip[0] - root[0]).abs() * rest.units.meters_per_unit as f32);
        start += count;
    }
    offsets.sort_by(f32::total_cmp);
    let median = offsets[offsets.len() / 2];
    assert!(
        median > 0.003,
        "the README's bake kept no visible set: median tip offset {median} m"
    );
}
