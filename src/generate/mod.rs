//! Procedural grooms, three layouts:
//!
//! - `scalp` and `swatch` (`cap`): test grooms, strands along the normal
//!   of an ellipsoid scalp cap (optionally draped toward -Y) or hanging from
//!   a bar; straight or waved with the elliptic-cone spiral of Agui et al.
//!   eq. (30)-(31). Unchanged since the samples and goldens were made.
//! - `head`: a groom that looks like hair, built the way groom tools
//!   (Houdini's Hair Generate and Guide Groom, XGen, Ornatrix) start one:
//!   roots spread evenly over a scalp region bounded by a hairline
//!   (`scalp`), combed along the head by a direction field with a parting
//!   and a crown whorl, lying on the head before hanging down under their
//!   own line (`comb`), with seeded per-strand variation of length,
//!   width and curl and clumps (`variation`).
//!
//! Coordinates are metres, Y up, the face toward +Z. The same parameters
//! and seed give the same groom bit for bit, for any thread count (fixed
//! SplitMix64 streams, one per strand, no platform randomness).

mod cap;
mod comb;
mod head;
mod scalp;
mod variation;

use groom::{Groom, Provenance, Units, UpAxis};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Where the roots are.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RootLayout {
    /// On the scalp cap of an ellipsoid head centred at `head_center`,
    /// growing along the surface normal.
    #[default]
    Scalp,
    /// Along a bar of width `swatch_width` at `head_center`, along X,
    /// hanging straight down (-Y). The paper's single-strand scenes.
    Swatch,
    /// A combed head of hair: roots inside a hairline on the ellipsoid head
    /// (or on `scalp_mesh`), lying along the head, then hanging.
    Head,
}

/// The shape of the strand around its axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum StrandShape {
    #[default]
    Straight,
    /// `x = A z cos(C z + D)`, `y = B z sin(C z + D)` around the straight
    /// axis, `z` the arc length from `wave_start`, `D` random per strand.
    Wavy,
}

/// Everything a generated groom depends on. Ranges and the sources of the
/// defaults are in README.md ("generate"); `check` enforces the ranges.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GeneratorParameters {
    pub layout: RootLayout,
    pub shape: StrandShape,
    pub strands: usize,
    /// Strand length, metres (for `head`, the mean).
    pub length: f32,
    /// Target segment length, metres; each strand gets `round(length / segment_length)` edges.
    pub segment_length: f32,
    pub seed: u64,
    pub head_center: [f32; 3],
    /// Ellipsoid semi-axes (x, y, z), metres; equal for a sphere.
    pub head_radii: [f32; 3],
    /// Largest polar angle of a root from +Y, degrees (the cap's size).
    pub scalp_angle: f32,
    /// Width of the swatch bar, metres.
    pub swatch_width: f32,
    /// Wave amplitude slopes A and B (dimensionless: radius grows A z).
    pub wave_amplitude: [f32; 2],
    /// Wave frequency C, radians per metre.
    pub wave_frequency: f32,
    /// Arc length from the root where the wave starts, metres.
    pub wave_start: f32,
    /// Hair width written as the `width` attribute, metres (for `head`, the mean).
    pub width: f32,
    /// Scalp strands bend from the root normal toward -Y at this rate,
    /// radians per metre, and are kept off the head: combed-down hair.
    /// 0 keeps them straight along the normal.
    pub drape: f32,

    // `head` only.
    /// A closed head mesh (`.obj`, `.glb`, `.gltf`, metres, Y up, face
    /// toward +Z) to root the hair on instead of the ellipsoid; its bounding
    /// box gives the head's centre and radii. In a timeline, relative to it.
    pub scalp_mesh: Option<PathBuf>,
    /// Polar angle of the hairline from the top of the head, degrees, at
    /// the front (forehead), the sides (above the ears) and the back (nape).
    pub hairline: [f32; 3],
    /// Where the parting runs, degrees from the top toward +X (0: a centre
    /// parting, 90 would be above the ear).
    pub parting: f32,
    /// The crown whorl's polar angle from the top toward the back, degrees.
    pub whorl_angle: f32,
    /// How far the hair turns around the whorl, degrees (+: clockwise seen
    /// from above).
    pub whorl_swirl: f32,
    /// Angle at which a strand leaves the scalp, degrees.
    pub lift: f32,
    /// Thickness of the hair layer on the head, metres: each strand lies at
    /// a random height up to this above the scalp.
    pub volume: f32,
    /// Arc length from the root that lies on the head however steep the
    /// scalp is (hair pressed down by the hair over it), metres.
    pub contact_length: f32,
    /// Relative standard deviation of the strand lengths.
    pub length_spread: f32,
    /// Relative standard deviation of the strand widths.
    pub width_spread: f32,
    /// Curls on or off.
    pub curl: bool,
    /// Mean curl (helix) radius, metres.
    pub curl_radius: f32,
    /// Relative standard deviation of the curl radius.
    pub curl_radius_spread: f32,
    /// Length along the strand's axis of one curl turn, metres.
    pub curl_pitch: f32,
    /// Phase of the curl at the root, degrees.
    pub curl_phase: f32,
    /// Each clump's phase (each strand's, without clumps) is `curl_phase`
    /// plus a uniform draw in plus or minus this, degrees (180: any phase).
    pub curl_phase_spread: f32,
    /// Mean distance between clump centres on the scalp, metres (0: no clumps).
    pub clump_size: f32,
    /// How far a strand's tip is drawn to its clump's centre strand, 0 to 1.
    pub clump_strength: f32,
    /// Clumping along the strand is `clump_strength (s / length)^clump_profile`:
    /// above 1 the clump gathers toward the tips, below 1 nearer the roots.
    pub clump_profile: f32,
}

impl Default for GeneratorParameters {
    fn default() -> Self {
        GeneratorParameters {
            layout: RootLayout::Scalp,
            shape: StrandShape::Straight,
            strands: 200,
            length: 0.24,
            segment_length: 0.01,
            seed: 1,
            head_center: [0.0, 0.0, 0.0],
            head_radii: [0.08, 0.1, 0.09],
            scalp_angle: 80.0,
            swatch_width: 0.05,
            wave_amplitude: [0.15, 0.1],
            wave_frequency: 60.0,
            wave_start: 0.03,
            width: 8.0e-5,
            drape: 0.0,
            scalp_mesh: None,
            hairline: [60.0, 100.0, 125.0],
            parting: 15.0,
            whorl_angle: 35.0,
            whorl_swirl: 40.0,
            lift: 15.0,
            volume: 0.003,
            contact_length: 0.04,
            length_spread: 0.15,
            width_spread: 0.15,
            curl: false,
            curl_radius: 0.01,
            curl_radius_spread: 0.15,
            curl_pitch: 0.03,
            curl_phase: 0.0,
            curl_phase_spread: 180.0,
            clump_size: 0.012,
            clump_strength: 0.5,
            clump_profile: 1.5,
        }
    }
}

/// Why parameters cannot make a groom.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("generator parameter '{name}': {message}")]
pub struct GeneratorError {
    pub name: &'static str,
    pub message: String,
}

/// The clearance every `head` vertex but the root keeps from the scalp,
/// metres: more than the mesh scalp's interpolation error (well under
/// 0.05 mm on `samples/head.obj`) and a few hair radii.
pub const CLEARANCE: f32 = 2e-4;

/// Largest number of standard deviations a drawn length, width or curl
/// radius is from its mean (a normal draw, clamped).
const SPREAD_CLAMP: f32 = 3.0;

impl GeneratorParameters {
    /// The largest edge count of a strand (for `head`, of the longest
    /// length the spread can draw).
    pub fn edges_per_strand(&self) -> usize {
        let longest = match self.layout {
            RootLayout::Head => self.length * (1.0 + SPREAD_CLAMP * self.length_spread.max(0.0)),
            _ => self.length,
        };
        ((longest / self.segment_length).round() as usize).max(1)
    }

    pub fn check(&self) -> Result<(), GeneratorError> {
        let fail = |name, message: &str| {
            Err(GeneratorError {
                name,
                message: message.to_string(),
            })
        };
        if self.strands == 0 || self.strands > 10_000_000 {
            return fail("strands", "must be between 1 and 10,000,000");
        }
        if !(self.length.is_finite() && self.length > 0.0) {
            return fail("length", "must be a positive length");
        }
        if !(self.segment_length.is_finite() && self.segment_length > 0.0) {
            return fail("segment_length", "must be a positive length");
        }
        if self.length / self.segment_length > 10_000.0 {
            return fail(
                "segment_length",
                "gives more than 10,000 segments per strand",
            );
        }
        if self.head_radii.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
            return fail("head_radii", "must be three positive lengths");
        }
        if !(self.scalp_angle.is_finite() && self.scalp_angle > 0.0 && self.scalp_angle <= 180.0) {
            return fail("scalp_angle", "must be in (0, 180] degrees");
        }
        let finite = self.head_center.iter().all(|c| c.is_finite())
            && self.wave_amplitude.iter().all(|c| c.is_finite())
            && self.wave_frequency.is_finite()
            && self.wave_start.is_finite()
            && self.swatch_width.is_finite()
            && self.width.is_finite()
            && self.drape.is_finite();
        if !finite {
            return fail("parameters", "every number must be finite");
        }
        if self.layout == RootLayout::Head {
            self.check_head()?;
        } else if let Some(name) = self.head_only_key_set() {
            return Err(GeneratorError {
                name,
                message: "applies to layout = \"head\" only".into(),
            });
        }
        // The product, not only each factor: 10 M strands of 10 k segments
        // would ask for a terabyte.
        let per_strand = self.edges_per_strand() as u64 + 1;
        if let Err(message) = crate::budget::check_vertices(self.strands as u64, per_strand) {
            return Err(GeneratorError {
                name: "strands",
                message,
            });
        }
        Ok(())
    }

    /// The first `head`-only parameter that differs from its default.
    fn head_only_key_set(&self) -> Option<&'static str> {
        let d = GeneratorParameters::default();
        let differs: [(&'static str, bool); 19] = [
            ("scalp_mesh", self.scalp_mesh != d.scalp_mesh),
            ("hairline", self.hairline != d.hairline),
            ("parting", self.parting != d.parting),
            ("whorl_angle", self.whorl_angle != d.whorl_angle),
            ("whorl_swirl", self.whorl_swirl != d.whorl_swirl),
            ("lift", self.lift != d.lift),
            ("volume", self.volume != d.volume),
            ("contact_length", self.contact_length != d.contact_length),
            ("length_spread", self.length_spread != d.length_spread),
            ("width_spread", self.width_spread != d.width_spread),
            ("curl", self.curl != d.curl),
            ("curl_radius", self.curl_radius != d.curl_radius),
            (
                "curl_radius_spread",
                self.curl_radius_spread != d.curl_radius_spread,
            ),
            ("curl_pitch", self.curl_pitch != d.curl_pitch),
            ("curl_phase", self.curl_phase != d.curl_phase),
            (
                "curl_phase_spread",
                self.curl_phase_spread != d.curl_phase_spread,
            ),
            ("clump_size", self.clump_size != d.clump_size),
            ("clump_strength", self.clump_strength != d.clump_strength),
            ("clump_profile", self.clump_profile != d.clump_profile),
        ];
        differs.iter().find(|(_, d)| *d).map(|(n, _)| *n)
    }

    /// The `head` layout's own ranges, and the other layouts' keys it
    /// does not use.
    fn check_head(&self) -> Result<(), GeneratorError> {
        let d = GeneratorParameters::default();
        let fail = |name, message: String| Err(GeneratorError { name, message });
        let not_for_head = [
            ("shape", self.shape != d.shape, "use curl"),
            (
                "drape",
                self.drape != d.drape,
                "the hair is combed and hangs by itself",
            ),
            (
                "scalp_angle",
                self.scalp_angle != d.scalp_angle,
                "use hairline",
            ),
            ("swatch_width", self.swatch_width != d.swatch_width, ""),
            (
                "wave_amplitude",
                self.wave_amplitude != d.wave_amplitude,
                "use curl",
            ),
            (
                "wave_frequency",
                self.wave_frequency != d.wave_frequency,
                "use curl",
            ),
            ("wave_start", self.wave_start != d.wave_start, "use curl"),
        ];
        for (name, set, instead) in not_for_head {
            if set {
                let instead = if instead.is_empty() {
                    String::new()
                } else {
                    format!(" ({instead})")
                };
                return fail(
                    name,
                    format!("does not apply to layout = \"head\"{instead}"),
                );
            }
        }
        if self.scalp_mesh.is_some() {
            for (name, set) in [
                ("head_center", self.head_center != d.head_center),
                ("head_radii", self.head_radii != d.head_radii),
            ] {
                if set {
                    return fail(
                        name,
                        "does not apply with scalp_mesh (the mesh's bounds give the head)".into(),
                    );
                }
            }
        }
        // name, value, low, high, unit
        let ranges: [(&'static str, f32, f32, f32, &str); 17] = [
            ("length", self.length, 0.01, 2.0, "m"),
            ("segment_length", self.segment_length, 1e-4, 0.05, "m"),
            ("width", self.width, 1e-5, 5e-4, "m"),
            ("parting", self.parting, -60.0, 60.0, "degrees"),
            ("whorl_angle", self.whorl_angle, 0.0, 80.0, "degrees"),
            ("whorl_swirl", self.whorl_swirl, -180.0, 180.0, "degrees"),
            ("lift", self.lift, 1.0, 60.0, "degrees"),
            ("volume", self.volume, CLEARANCE, 0.05, "m"),
            ("contact_length", self.contact_length, 0.0, 0.3, "m"),
            ("length_spread", self.length_spread, 0.0, 0.3, ""),
            ("width_spread", self.width_spread, 0.0, 0.3, ""),
            ("curl_radius", self.curl_radius, 0.001, 0.05, "m"),
            ("curl_radius_spread", self.curl_radius_spread, 0.0, 0.3, ""),
            ("curl_pitch", self.curl_pitch, 0.002, 0.5, "m"),
            ("curl_phase", self.curl_phase, -360.0, 360.0, "degrees"),
            (
                "curl_phase_spread",
                self.curl_phase_spread,
                0.0,
                180.0,
                "degrees",
            ),
            ("clump_profile", self.clump_profile, 0.1, 10.0, ""),
        ];
        for (name, value, low, high, unit) in ranges {
            if !(value.is_finite() && (low..=high).contains(&value)) {
                let unit = if unit.is_empty() {
                    String::new()
                } else {
                    format!(" {unit}")
                };
                return fail(
                    name,
                    format!("{value} is outside its range, {low} to {high}{unit}"),
                );
            }
        }
        for (i, angle) in self.hairline.iter().enumerate() {
            if !(angle.is_finite() && (30.0..=170.0).contains(angle)) {
                return fail(
                    "hairline",
                    format!(
                        "{} angle {angle} is outside its range, 30 to 170 degrees",
                        ["front", "side", "back"][i]
                    ),
                );
            }
        }
        if !(self.clump_size.is_finite()
            && (self.clump_size == 0.0 || (0.002..=0.1).contains(&self.clump_size)))
        {
            return fail(
                "clump_size",
                format!(
                    "{} is outside its range: 0 (no clumps) or 0.002 to 0.1 m",
                    self.clump_size
                ),
            );
        }
        if self.curl && self.segment_length > self.curl_pitch / 4.0 {
            return fail(
                "segment_length",
                format!(
                    "{} m is too long to draw a curl of pitch {} m: at most a quarter of curl_pitch",
                    self.segment_length, self.curl_pitch
                ),
            );
        }
        if !(self.clump_strength.is_finite() && (0.0..=1.0).contains(&self.clump_strength)) {
            return fail(
                "clump_strength",
                format!("{} is outside its range, 0 to 1", self.clump_strength),
            );
        }
        Ok(())
    }
}

/// The groom every layout fills: metres, Y up, marked as generated.
fn empty_groom() -> Groom {
    Groom {
        units: Units::METERS,
        up_axis: UpAxis::Y,
        provenance: Provenance {
            format: "generated".into(),
            ..Default::default()
        },
        ..Groom::default()
    }
}

/// Builds the groom. Also writes the per-strand `root_uv` and the
/// per-vertex `width` attributes (see each layout's module).
pub fn generate(parameters: &GeneratorParameters) -> Result<Groom, GeneratorError> {
    parameters.check()?;
    match parameters.layout {
        RootLayout::Head => head::generate_head(parameters),
        RootLayout::Scalp | RootLayout::Swatch => Ok(cap::generate_cap(parameters)),
    }
}

/// A small, fixed pseudo-random stream (SplitMix64) so generated grooms are
/// the same on every platform and crate version.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> SplitMix64 {
        SplitMix64(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A stream of its own for item `index` of stream `stream` of `seed`:
    /// per-strand streams make a strand's draws independent of the order
    /// in which threads build the strands.
    pub fn for_item(seed: u64, stream: u64, index: u64) -> SplitMix64 {
        let mut mix = SplitMix64(seed ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let base = mix.next_u64();
        let mut mix = SplitMix64(base ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        SplitMix64(mix.next_u64())
    }

    /// A normal draw of mean 1 and standard deviation `spread`, clamped to
    /// `SPREAD_CLAMP` deviations (and to at least 0.05).
    pub fn relative(&mut self, spread: f32) -> f64 {
        let c = SPREAD_CLAMP as f64;
        (1.0 + spread as f64 * self.next_normal().clamp(-c, c)).max(0.05)
    }

    /// Standard normal (Box-Muller).
    pub fn next_normal(&mut self) -> f64 {
        let u1 = self.next_f64().max(f64::MIN_POSITIVE);
        let u2 = self.next_f64();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_groom() {
        let parameters = GeneratorParameters {
            strands: 50,
            ..Default::default()
        };
        let a = generate(&parameters).unwrap();
        let b = generate(&parameters).unwrap();
        assert_eq!(a, b);
        let c = generate(&GeneratorParameters {
            seed: 2,
            ..parameters
        })
        .unwrap();
        assert_ne!(a.points, c.points);
    }

    #[test]
    fn roots_on_head_and_lengths_kept() {
        let parameters = GeneratorParameters {
            strands: 20,
            shape: StrandShape::Wavy,
            ..Default::default()
        };
        let groom = generate(&parameters).unwrap();
        assert!(groom.validate().is_empty());
        assert_eq!(groom.strand_count(), 20);
        for strand in groom.strands() {
            let r = strand[0];
            let radii = parameters.head_radii;
            let on =
                (r[0] / radii[0]).powi(2) + (r[1] / radii[1]).powi(2) + (r[2] / radii[2]).powi(2);
            assert!((on - 1.0).abs() < 1e-4, "root off the head: {on}");
            assert!(r[1] >= radii[1] * (80f32.to_radians().cos()) - 1e-5);
            let length: f32 = strand
                .windows(2)
                .map(|w| {
                    ((w[1][0] - w[0][0]).powi(2)
                        + (w[1][1] - w[0][1]).powi(2)
                        + (w[1][2] - w[0][2]).powi(2))
                    .sqrt()
                })
                .sum();
            assert!((length - 0.24).abs() < 1e-4, "length {length}");
        }
    }

    #[test]
    fn wave_follows_elliptic_cone() {
        let parameters = GeneratorParameters {
            strands: 1,
            layout: RootLayout::Swatch,
            shape: StrandShape::Wavy,
            wave_start: 0.0,
            ..Default::default()
        };
        let groom = generate(&parameters).unwrap();
        let tip = groom.points[groom.points.len() - 1];
        // The spiral leaves the axis by at most A z (A the larger slope).
        let off_axis = (tip[0].powi(2) + tip[2].powi(2)).sqrt();
        assert!(
            off_axis > 0.0 && off_axis <= 0.15 * 0.24 + 1e-4,
            "{off_axis}"
        );
    }

    #[test]
    fn draped_hair_hangs_and_stays_off_the_head() {
        let parameters = GeneratorParameters {
            strands: 30,
            drape: 20.0,
            ..Default::default()
        };
        let groom = generate(&parameters).unwrap();
        let radii = parameters.head_radii;
        for strand in groom.strands() {
            let tip = strand[strand.len() - 1];
            assert!(tip[1] < strand[0][1], "tip not below root");
            for p in &strand[1..] {
                let r = (p[0] / radii[0]).powi(2)
                    + (p[1] / radii[1]).powi(2)
                    + (p[2] / radii[2]).powi(2);
                assert!(r >= 1.0, "inside the head: {r}");
            }
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let error = generate(&GeneratorParameters {
            strands: 0,
            ..Default::default()
        })
        .unwrap_err();
        assert_eq!(error.name, "strands");
        let error = generate(&GeneratorParameters {
            segment_length: -1.0,
            ..Default::default()
        })
        .unwrap_err();
        assert_eq!(error.name, "segment_length");
    }
}
