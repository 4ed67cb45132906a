//! `samples/wind.toml` on the combed head (issue 34 item 2): the stochastic
//! wind of 001_* moves the hair without entering the head at any frame.
//! The test bakes the sample's own timeline with fewer strands (the wind
//! model moves each hair on its own, so each behaves as in the full sample)
//! and reads back the animated Alembic it writes.

use crate::util::{sample, TestDir};

const STRANDS: usize = 1000;

/// The head ellipsoid of the sample (the groom's and the wind's), metres.
const RADII: [f64; 3] = [0.08, 0.1, 0.09];

/// `sum (p / radii)^2`: below 1 inside the head.
fn level(p: [f32; 3]) -> f64 {
    (0..3).map(|k| (p[k] as f64 / RADII[k]).powi(2)).sum()
}

fn distance(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| (a[k] as f64 - b[k] as f64).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// The sample's timeline with `strands` strands, its exports unchanged.
fn reduced(strands: usize) -> String {
    let text = std::fs::read_to_string(sample("wind.toml")).unwrap();
    assert!(
        text.contains("layout = \"head\""),
        "wind.toml: not a head groom"
    );
    let key = "strands = ";
    let start = text.find(key).expect("a generated groom") + key.len();
    let digits = text[start..]
        .find(|c: char| !c.is_ascii_digit())
        .expect("a strand count");
    format!("{}{strands}{}", &text[..start], &text[start + digits..])
}

#[test]
fn wind_on_the_combed_head_never_enters_the_head_and_spreads_the_hair() {
    let dir = TestDir::new();
    std::fs::write(dir.path("wind.toml"), reduced(STRANDS)).unwrap();
    dir.run_ok(&["bake", "wind.toml", "-q"]);
    let groom = importers::read(&dir.path("out/wind.abc")).unwrap();
    assert_eq!(groom.strand_count(), STRANDS);
    // The rest pose and the paper's 10 model frames.
    assert_eq!(groom.frames.len(), 11);

    // Nothing inside the head at any frame. The roots lie on it: allow the
    // file's f32 rounding (a level of 1 - 2e-6 is 0.1 um deep).
    let mut deepest = f64::INFINITY;
    for (f, frame) in groom.frames.iter().enumerate() {
        let inside = frame
            .points
            .iter()
            .filter(|&&p| level(p) < 1.0 - 2e-6)
            .count();
        assert_eq!(inside, 0, "frame {f}: {inside} vertices inside the head");
        deepest = frame
            .points
            .iter()
            .map(|&p| level(p))
            .fold(deepest, f64::min);
    }

    // The wind moves the hair: the mean motion per frame, and how far the
    // hair went from its combed shape by the last frame.
    let motion: Vec<f64> = groom
        .frames
        .windows(2)
        .map(|w| {
            w[0].points
                .iter()
                .zip(&w[1].points)
                .map(|(&a, &b)| distance(a, b))
                .sum::<f64>()
                / w[0].points.len() as f64
        })
        .collect();
    let (first, last) = (&groom.frames[0].points, &groom.frames[10].points);
    let spread = first
        .iter()
        .zip(last)
        .map(|(&a, &b)| distance(a, b))
        .sum::<f64>()
        / first.len() as f64;
    let peak = motion.iter().copied().fold(0.0, f64::max);
    let after_6 = motion[6..].iter().copied().fold(0.0, f64::max);
    eprintln!(
        "wind on the head: lowest level {deepest:.9}; mean motion per frame (mm) {:?}; \
         after frame 6 at most {:.2} of the peak; mean displacement {:.1} mm",
        motion
            .iter()
            .map(|m| (m * 1e4).round() / 10.0)
            .collect::<Vec<_>>(),
        after_6 / peak,
        spread * 1e3
    );
    assert!(spread > 0.01, "the wind moved the hair only {spread} m");
}
