use super::*;
use crate::generate::{generate, GeneratorParameters, RootLayout, StrandShape};

fn head(strands: usize, shape: StrandShape) -> Groom {
    generate(&GeneratorParameters {
        strands,
        shape,
        ..GeneratorParameters::default()
    })
    .unwrap()
}

#[test]
fn writes_looks() {
    let dir = std::path::Path::new("/tmp/preview-look");
    std::fs::create_dir_all(dir).unwrap();
    for (name, groom) in [
        ("straight", head(20000, StrandShape::Straight)),
        ("wavy", head(20000, StrandShape::Wavy)),
        ("few", head(100, StrandShape::Wavy)),
        (
            "swatch",
            generate(&GeneratorParameters {
                strands: 5000,
                layout: RootLayout::Swatch,
                shape: StrandShape::Wavy,
                ..GeneratorParameters::default()
            })
            .unwrap(),
        ),
    ] {
        for view in [View::Front, View::Side, View::Top, View::Persp] {
            let options = PreviewOptions {
                width: 512,
                height: 512,
                view,
                ..PreviewOptions::default()
            };
            let image = render(&groom, &options).unwrap();
            write_png(&image, &dir.join(format!("{name}-{view:?}.png"))).unwrap();
        }
    }
    let _ = RootLayout::Swatch;
}
