//! The timeline's hold (`crate::sim::Hold`): `[material] hold` and
//! `hold_ramp`, replaced per stage by the stage's own; checked before any
//! simulation, and a stage's hold for its plan.

use super::schema::{StageKind, StageSpec, TimelineFile};
use super::{Timeline, TimelineError};
use crate::sim::Hold;
use serde_spanned::Spanned;

/// The hold of a stage: its own `hold`/`hold_ramp` where given, else the
/// material's; `None` when the strength is 0 or not given (off), and in a
/// wind stage (the stochastic wind moves the hair itself).
pub fn of_stage(file: &TimelineFile, stage: &StageSpec) -> Option<Hold> {
    if *stage.kind.get_ref() == StageKind::Wind {
        return None;
    }
    let strength = stage
        .hold
        .as_ref()
        .or(file.material.hold.as_ref())
        .map(|h| *h.get_ref())?;
    let ramp = stage
        .hold_ramp
        .as_ref()
        .or(file.material.hold_ramp.as_ref())
        .map_or([1.0, 1.0], |r| *r.get_ref());
    (strength > 0.0).then_some(Hold { strength, ramp })
}

/// Checks every hold of the timeline: strengths finite and in [0, 1e8]
/// 1/s^2, ramps of two shares in [0, 1], not both 0, and no ramp or stage
/// hold where it cannot apply (no hold in that stage, a wind stage).
pub fn check(timeline: &Timeline) -> Result<(), TimelineError> {
    let file = &timeline.file;
    let material = &file.material;
    if let Some(h) = &material.hold {
        check_strength(timeline, "[material] hold", h)?;
    }
    if let Some(r) = &material.hold_ramp {
        check_ramp(timeline, "[material] hold_ramp", r)?;
        let held_somewhere = file
            .stages
            .get_ref()
            .iter()
            .any(|s| s.hold_ramp.is_none() && of_stage(file, s).is_some());
        if !held_somewhere {
            return Err(timeline.error_at(
                r.span(),
                "[material] hold_ramp applies only with a hold: set `hold` (1/s^2) in [material] or in a stage, or remove hold_ramp",
            ));
        }
    }
    for stage in file.stages.get_ref() {
        let kind = *stage.kind.get_ref();
        if let Some(h) = &stage.hold {
            check_strength(timeline, "the stage's hold", h)?;
            if kind == StageKind::Wind {
                return Err(timeline.error_at(
                    h.span(),
                    "`hold` does not apply to wind stages (the stochastic wind moves the hair itself)",
                ));
            }
        }
        if let Some(r) = &stage.hold_ramp {
            check_ramp(timeline, "the stage's hold_ramp", r)?;
            if of_stage(file, stage).is_none() {
                return Err(timeline.error_at(
                    r.span(),
                    format!(
                        "hold_ramp applies only with a hold, and this {} stage has none: set `hold` (1/s^2) here or in [material], or remove hold_ramp",
                        kind.name()
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn check_strength(
    timeline: &Timeline,
    key: &str,
    hold: &Spanned<f32>,
) -> Result<(), TimelineError> {
    let k = *hold.get_ref();
    if k.is_finite() && (0.0..=Hold::MAX_STRENGTH).contains(&k) {
        return Ok(());
    }
    Err(timeline.error_at(
        hold.span(),
        format!(
            "{key} must be an acceleration per metre of displacement in [0, 1e8] 1/s^2 (0: off; 1e4 holds a hair within 1 mm against gravity), not {k}"
        ),
    ))
}

fn check_ramp(
    timeline: &Timeline,
    key: &str,
    ramp: &Spanned<[f32; 2]>,
) -> Result<(), TimelineError> {
    let r = *ramp.get_ref();
    if r.iter()
        .any(|v| !(v.is_finite() && (0.0..=1.0).contains(v)))
    {
        return Err(timeline.error_at(
            ramp.span(),
            format!("{key} must be two shares of the hold in [0, 1], [root, tip], not {r:?}"),
        ));
    }
    if r == [0.0, 0.0] {
        return Err(timeline.error_at(
            ramp.span(),
            format!("{key} [0, 0] holds nothing: set hold = 0 to switch the hold off"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timeline::bake::{bake, BakeOptions};

    const SWATCH: &str = r#"
seed = 1

[groom]
generate = { layout = "swatch", strands = 24, length = 0.04, segment_length = 0.005, swatch_width = 0.04, head_center = [0.0, 0.30, 0.0] }

[material]
HOLD

[solver]
dt = "1/360"
iterations = 5

[[collider]]
name = "pillow"
active = "listed"
shape = { cuboid = { half_extents = [0.15, 0.05, 0.15] } }
friction = 0.5
motion = [
  { t = 0.3, translation = [0.0, 0.17, 0.0], rotation = [0.0, 0.0, 25.0] },
  { t = 1.3, translation = [0.0, 0.225, 0.0], rotation = [0.0, 0.0, 25.0] },
]

[[stage]]
kind = "wet"
duration = 0.3

[[stage]]
kind = "press"
duration = 1.2
colliders = ["pillow"]
"#;

    fn parse(text: &str) -> Result<Timeline, TimelineError> {
        Timeline::parse(std::path::Path::new("hold.toml"), text.to_string())
    }

    fn swatch(hold: &str) -> String {
        SWATCH.replace("HOLD", hold)
    }

    #[test]
    fn a_bad_hold_names_its_key_and_place() {
        for (material, what) in [
            ("hold = -1.0", "[material] hold must be"),
            ("hold = nan", "[material] hold must be"),
            ("hold = inf", "[material] hold must be"),
            ("hold = 1e9", "[material] hold must be"),
            (
                "hold = 100.0\nhold_ramp = [1.0, 2.0]",
                "hold_ramp must be two shares",
            ),
            ("hold = 100.0\nhold_ramp = [0.0, 0.0]", "holds nothing"),
            ("hold_ramp = [1.0, 0.5]", "applies only with a hold"),
        ] {
            let e = parse(&swatch(material)).unwrap_err();
            assert!(e.message.contains(what), "{material}: {e}");
            // The line of the offending key (the [material] table's, 8-9).
            assert!((8..=9).contains(&e.line), "{material}: {e}");
        }
        let stage = swatch("").replace("kind = \"press\"", "kind = \"press\"\nhold = -5.0");
        let e = parse(&stage).unwrap_err();
        assert!(e.message.contains("the stage's hold must be"), "{e}");
        let ramp = swatch("").replace(
            "kind = \"press\"",
            "kind = \"press\"\nhold_ramp = [1.0, 0.0]",
        );
        let e = parse(&ramp).unwrap_err();
        assert!(e.message.contains("this press stage has none"), "{e}");
    }

    #[test]
    fn a_stage_replaces_the_material_hold() {
        let text = swatch("hold = 500.0\nhold_ramp = [0.5, 1.0]")
            .replace("kind = \"press\"", "kind = \"press\"\nhold = 0.0");
        let timeline = parse(&text).unwrap();
        let stages = timeline.file.stages.get_ref();
        assert_eq!(
            of_stage(&timeline.file, &stages[0]),
            Some(Hold {
                strength: 500.0,
                ramp: [0.5, 1.0]
            })
        );
        assert_eq!(of_stage(&timeline.file, &stages[1]), None);
        assert_eq!(
            of_stage(&parse(&swatch("")).unwrap().file, &stages[0]),
            None
        );
    }

    /// The mean distance of the tips from where they were groomed after the
    /// press, metres, and the bake's report of the press stage's hold.
    fn pressed(hold: &str) -> (f32, Option<Hold>) {
        let timeline = parse(&swatch(hold)).unwrap();
        let options = BakeOptions {
            dry: true,
            ..BakeOptions::default()
        };
        let outcome = bake(&timeline, &options).unwrap();
        let before = &outcome.snapshots[0].1;
        let (label, after) = outcome.snapshots.last().unwrap();
        assert_eq!(label, "after press");
        let offsets = before.strand_offsets();
        let tips: Vec<usize> = offsets.windows(2).map(|w| w[1] - 1).collect();
        let moved = tips
            .iter()
            .map(|&t| {
                let (a, b) = (before.points[t], after.points[t]);
                (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f32>().sqrt()
            })
            .sum::<f32>()
            / tips.len() as f32;
        (moved, outcome.report.stages[1].hold)
    }

    #[test]
    fn a_pillow_press_still_moves_held_hair() {
        // The pillow is a collider: the hair goes where it pushes it, hold or
        // not (a hold that pinned the hair would leave it inside the pillow).
        let (free, none) = pressed("");
        // The hold that keeps the Bangs (sim/hold_tests.rs `BANGS_HOLD`).
        let k = 1.0e5;
        let (held, reported) = pressed(&format!("hold = {k}"));
        eprintln!(
            "pillow press: tips moved {:.2} mm without a hold, {:.2} mm with hold {k} 1/s^2",
            free * 1e3,
            held * 1e3
        );
        assert_eq!(none, None);
        assert_eq!(reported, Some(Hold::uniform(k)));
        assert!(free > 5e-3, "{free}");
        assert!(held > 0.8 * free, "{held} against {free}");
    }
}
