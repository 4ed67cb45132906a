//! Writes preview pictures of generated grooms into a folder, to look at:
//! `cargo run --release --example preview_gallery -- /tmp/look`.

use groom::{Attribute, AttributeValues, Groom};
use groombake::generate::{generate, GeneratorParameters, RootLayout, StrandShape};
use groombake::preview::{render, render_sheet, write_png, PreviewOptions, SheetEntry, View};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .ok_or("usage: preview_gallery DIR")?,
    );
    std::fs::create_dir_all(&dir)?;
    let make = |strands, layout, shape| {
        generate(&GeneratorParameters {
            strands,
            layout,
            shape,
            ..GeneratorParameters::default()
        })
    };
    let grooms: Vec<(&str, Groom)> = vec![
        (
            "straight",
            make(20_000, RootLayout::Scalp, StrandShape::Straight)?,
        ),
        ("wavy", make(20_000, RootLayout::Scalp, StrandShape::Wavy)?),
        ("few", make(100, RootLayout::Scalp, StrandShape::Wavy)?),
        (
            "swatch",
            make(5_000, RootLayout::Swatch, StrandShape::Wavy)?,
        ),
    ];
    for (name, groom) in &grooms {
        for view in [View::Front, View::Side, View::Top, View::Persp] {
            let options = PreviewOptions {
                width: 512,
                height: 512,
                view,
                ..PreviewOptions::default()
            };
            write_png(
                &render(groom, &options)?,
                &dir.join(format!("{name}-{view:?}.png")),
            )?;
        }
    }
    // Coloured by height, as a bond rate would be.
    let mut coloured = make(20_000, RootLayout::Scalp, StrandShape::Wavy)?;
    let heights: Vec<f32> = coloured.points.iter().map(|p| p[1]).collect();
    coloured.set_attribute(Attribute::new(
        "bond_hydrogen",
        AttributeValues::Float(heights),
    ));
    let options = PreviewOptions {
        width: 640,
        height: 480,
        view: View::Persp,
        color_by: Some("bond_hydrogen".into()),
        ..PreviewOptions::default()
    };
    write_png(&render(&coloured, &options)?, &dir.join("coloured.png"))?;
    // A contact sheet of a swatch swinging to +X, coloured by strand.
    let mut swing = make(2_000, RootLayout::Swatch, StrandShape::Wavy)?;
    let order: Vec<f32> = (0..swing.strand_count()).map(|s| s as f32).collect();
    swing.set_attribute(Attribute::per_strand(
        "strand",
        AttributeValues::Float(order),
    ));
    swing.frames = (0..3)
        .map(|f| groom::Frame {
            time: f as f64,
            points: swing
                .points
                .iter()
                .map(|p| [p[0] - 0.4 * f as f32 * p[1], p[1], p[2]])
                .collect(),
            attributes: Vec::new(),
        })
        .collect();
    let labels = ["frame 0", "frame 1", "frame 2"];
    let entries: Vec<SheetEntry> = labels
        .iter()
        .enumerate()
        .map(|(frame, label)| SheetEntry {
            label,
            groom: &swing,
            frame: Some(frame),
            surfaces: &[],
        })
        .collect();
    let options = PreviewOptions {
        width: 320,
        height: 320,
        view: View::Front,
        color_by: Some("strand".into()),
        ..PreviewOptions::default()
    };
    write_png(&render_sheet(&entries, &options)?, &dir.join("sheet.png"))?;
    Ok(())
}
