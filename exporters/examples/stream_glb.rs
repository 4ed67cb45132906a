//! Measures a streamed animated glTF export: writes FRAMES frames of a
//! groom of STRANDS strands x POINTS points to OUT and prints the time and
//! sizes; run under `/usr/bin/time -v` to see that peak memory follows one
//! frame, not the animation.
//!
//!     cargo run --release -p exporters --example stream_glb -- OUT.glb 10000 25 200

use exporters::{animated, AnimationOptions};
use groom::{Frame, Groom, Units};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, out, strands, points, frames] = args.as_slice() else {
        return Err("usage: stream_glb OUT.glb STRANDS POINTS FRAMES".into());
    };
    let (strands, points, frames): (usize, usize, usize) =
        (strands.parse()?, points.parse()?, frames.parse()?);
    let mut groom = Groom::from_strands((0..strands).map(|s| {
        let x = (s % 100) as f32 * 0.1;
        let z = (s / 100) as f32 * 0.1;
        (0..points)
            .map(|k| [x, 30.0 - k as f32 * 0.5, z])
            .collect::<Vec<_>>()
    }));
    groom.units = Units::CENTIMETERS;
    let options = AnimationOptions {
        fps: 24.0,
        frame_count: frames,
    };
    let start = Instant::now();
    let mut writer = animated(out.as_ref(), &groom, options)?;
    let mut frame = Frame {
        time: 0.0,
        points: groom.points.clone(),
        attributes: Vec::new(),
    };
    for k in 0..frames {
        frame.time = k as f64 / 24.0;
        for (p, rest) in frame.points.iter_mut().zip(&groom.points) {
            p[0] = rest[0] + (k as f32 * 0.1 + rest[1] * 0.05).sin();
        }
        writer.write_frame(&frame)?;
    }
    writer.finish()?;
    let seconds = start.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(out)?.len();
    let frame_bytes = 12 * groom.vertex_count();
    println!(
        "{frames} frames x {} points: {bytes} bytes in {seconds:.2} s ({:.0} MB/s); one frame = {frame_bytes} bytes",
        groom.vertex_count(),
        bytes as f64 / seconds / 1e6
    );
    Ok(())
}
