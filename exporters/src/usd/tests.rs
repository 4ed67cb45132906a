use super::*;
use groom::{Attribute, Groom, Units, UpAxis};

pub(crate) fn sample_groom() -> Groom {
    let mut groom = Groom::from_strands([
        vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.5]],
        vec![[1.0, 0.0, 0.0], [1.0, 1.5, 0.0]],
    ]);
    groom.units = Units::CENTIMETERS;
    groom.up_axis = UpAxis::Z;
    groom.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float(vec![0.1, 0.08, 0.05, 0.1, 0.06]),
    ));
    groom.set_attribute(Attribute::new(
        "wetness",
        AttributeValues::Float(vec![0.0, 0.5, 1.0, 0.25, 0.75]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "root_uv",
        AttributeValues::Vec2(vec![[0.1, 0.2], [0.3, 0.4]]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "group id",
        AttributeValues::Int(vec![3, 4]),
    ));
    groom.set_attribute(Attribute::new(
        "rest",
        AttributeValues::Vec3(vec![[1.0, 2.0, 3.0]; 5]),
    ));
    groom
}

pub(crate) fn animated_groom(frames: usize) -> Groom {
    let mut groom = sample_groom();
    for i in 0..frames {
        let points = groom
            .points
            .iter()
            .map(|p| [p[0] + i as f32 * 0.5, p[1], p[2]])
            .collect();
        groom.frames.push(Frame {
            time: i as f64 / 24.0,
            points,
        });
    }
    groom
}

#[test]
fn writes_sample_files() {
    let dir = std::env::temp_dir().join("groombake-usd-samples");
    std::fs::create_dir_all(&dir).unwrap();
    for ext in ["usda", "usdc"] {
        crate::write(&dir.join(format!("static.{ext}")), &sample_groom()).unwrap();
        crate::write(&dir.join(format!("animated.{ext}")), &animated_groom(3)).unwrap();
    }
}
