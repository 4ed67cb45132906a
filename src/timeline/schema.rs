//! The TOML form of a timeline: serde types with unknown keys rejected.
//! Values that are checked after parsing keep their span so an error can
//! name the line and column.

use crate::generate::GeneratorParameters;
use serde::Deserialize;
use serde_spanned::Spanned;
use std::collections::BTreeMap;

/// A whole timeline file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimelineFile {
    /// Seed of every random process (the wind model); `--seed` overrides it.
    #[serde(default)]
    pub seed: Option<u64>,
    pub groom: GroomSpec,
    #[serde(default)]
    pub material: MaterialSpec,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default, rename = "collider")]
    pub colliders: Vec<ColliderSpec>,
    #[serde(rename = "stage")]
    pub stages: Spanned<Vec<StageSpec>>,
    #[serde(default, rename = "export")]
    pub exports: Vec<ExportSpec>,
    /// A contact sheet of the groom before and after each stage.
    pub preview: Option<PreviewSpec>,
}

/// The bake's contact sheet: one picture before the first stage and one
/// after each stage, side by side with labels.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PreviewSpec {
    /// The PNG to write, relative to `--out`.
    pub sheet: Spanned<String>,
    /// Colour strands by this attribute (e.g. `bond_hydrogen`, `wetness`).
    pub color: Option<Spanned<String>>,
    /// Size of each picture, pixels.
    #[serde(default = "default_preview_size")]
    pub size: Spanned<[u32; 2]>,
    /// `front`, `side`, `top`, `persp`, or `auto` (the default): the axis
    /// view that shows most of the change from before to after the bake.
    #[serde(default = "default_preview_view")]
    pub view: Spanned<String>,
    /// Draw the strands resampled along their smooth curves, a point every
    /// this many metres (as an export's `resample`).
    pub resample: Option<f32>,
}

fn default_preview_size() -> Spanned<[u32; 2]> {
    Spanned::new(0..0, [512, 512])
}

/// `[preview] view = "auto"`: see [`PreviewSpec::view`].
pub const AUTO_VIEW: &str = "auto";

fn default_preview_view() -> Spanned<String> {
    Spanned::new(0..0, AUTO_VIEW.to_string())
}

/// Where the groom comes from: a file (any importer, including a `state`
/// export of an earlier bake) or the generator.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroomSpec {
    /// A groom file, relative to the timeline file.
    pub source: Option<Spanned<String>>,
    /// Generator parameters (metres), instead of a file.
    pub generate: Option<Spanned<GeneratorParameters>>,
    /// Units of the source when the format does not say (`m`, `cm`, ...).
    pub units: Option<Spanned<String>>,
    /// Up axis of the source when the format does not say (`y` or `z`).
    pub up: Option<Spanned<String>>,
    /// Moves the groom after import (metres).
    #[serde(default)]
    pub translate: [f32; 3],
    /// Keyframed motion of the scalp (global seconds): the roots follow
    /// this rigid transform of where they start. Give a head collider the
    /// same keys so it moves along.
    #[serde(default = "no_motion")]
    pub motion: Spanned<Vec<KeySpec>>,
    /// Picks guides from a dense source groom; the other strands become
    /// render strands that follow them.
    pub guides: Option<Spanned<GuidesSpec>>,
    /// Grows render strands between the guides.
    pub render: Option<Spanned<RenderSpec>>,
}

/// Bond influences `f_j` (fractions of the restoring force).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BondInfluences {
    pub hydrogen: f32,
    pub ionic: f32,
    pub disulfide: f32,
    pub peptide: f32,
}

impl Default for BondInfluences {
    /// The paper's scene 3 split (hydrogen + ionic 63 %, disulfide 20 %,
    /// peptide 17 %), with hydrogen 35 % and ionic 28 % (METHOD G's choice).
    fn default() -> Self {
        BondInfluences {
            hydrogen: 0.35,
            ionic: 0.28,
            disulfide: 0.20,
            peptide: 0.17,
        }
    }
}

impl BondInfluences {
    pub fn as_array(&self) -> [f32; 4] {
        [self.hydrogen, self.ionic, self.disulfide, self.peptide]
    }
}

/// Material; defaults are real human hair (physical model) and the
/// paper's Table 1 (bonds, cuticle, `k_o` of the paper model).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialSpec {
    /// `"physical"` (real units, the default) or `"paper"` (000's `k_o`).
    pub model: Spanned<crate::sim::Model>,
    /// Bending/twisting stiffness `k_o` at the root, in [0, 1] (paper model).
    pub stiffness: Spanned<f32>,
    /// Young's modulus, Pa (physical model).
    pub youngs_modulus: Spanned<f32>,
    /// Shear modulus, Pa; default `youngs_modulus / (2 (1 + poisson_ratio))`.
    pub shear_modulus: Option<Spanned<f32>>,
    pub poisson_ratio: Spanned<f32>,
    /// Density, kg/m^3.
    pub density: Spanned<f32>,
    /// Fibre radius, metres; default: half the groom's `width`, else 40 um.
    pub radius: Option<Spanned<f32>>,
    /// Cuticle peel rate: the fraction of cuticle lost per centimetre from the root.
    pub cuticle_peel_per_cm: Spanned<f32>,
    pub bonds: Spanned<BondInfluences>,
    /// The hold toward the groomed shape, 1/s^2 (`crate::sim::Hold`): off
    /// when absent or 0; a stage's `hold` replaces it.
    pub hold: Option<Spanned<f32>>,
    /// The hold's shares at the root and the tip, each in [0, 1] (default
    /// `[1, 1]`); a stage's `hold_ramp` replaces it.
    pub hold_ramp: Option<Spanned<[f32; 2]>>,
}

impl Default for MaterialSpec {
    fn default() -> Self {
        MaterialSpec {
            model: Spanned::new(0..0, crate::sim::Model::Physical),
            stiffness: Spanned::new(0..0, 0.05),
            youngs_modulus: Spanned::new(0..0, 3.5e9),
            shear_modulus: None,
            poisson_ratio: Spanned::new(0..0, 0.3),
            density: Spanned::new(0..0, 1300.0),
            radius: None,
            cuticle_peel_per_cm: Spanned::new(0..0, 0.0033),
            bonds: Spanned::new(0..0, BondInfluences::default()),
            hold: None,
            hold_ramp: None,
        }
    }
}

/// A time step written as seconds or as a fraction `"1/360"`.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum TimeStep {
    Seconds(f64),
    Text(String),
}

impl TimeStep {
    pub fn seconds(&self) -> Option<f64> {
        match self {
            TimeStep::Seconds(s) => Some(*s),
            TimeStep::Text(text) => match text.split_once('/') {
                Some((n, d)) => {
                    let n: f64 = n.trim().parse().ok()?;
                    let d: f64 = d.trim().parse().ok()?;
                    Some(n / d)
                }
                None => text.trim().parse().ok(),
            },
        }
    }
}

/// Damping rates, per second.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DampingSpec {
    pub linear: f32,
    pub angular: f32,
}

/// Hair-hair: the pairwise penalty of (20) (guides, sparse hair) or the
/// volumetric mode (dense grooms; `crate::sim::Volumetric`).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HairHairSpec {
    #[serde(default)]
    pub mode: HairHairMode,
    /// `alpha` of (20), m/s^2 (pairwise mode).
    #[serde(default)]
    pub strength: f32,
    /// Grid cell edge, metres (volumetric mode).
    pub cell_size: Option<f32>,
    /// Velocity smoothing rate, per second (volumetric mode).
    pub smoothing: Option<f32>,
    /// Push down the hair's volume fraction gradient, m^2/s^2 (volumetric).
    pub repulsion: Option<f32>,
    /// Coulomb friction coefficient between hairs (pairwise mode, physical
    /// model): 0 (off) or 0.05 - 0.5; `None`: [`DEFAULT_HAIR_FRICTION`].
    pub friction: Option<f32>,
    /// Friction through the grid, 1/s per unit volume fraction
    /// (volumetric mode): see `Volumetric::friction`.
    pub grid_friction: Option<f32>,
}

/// Hair-on-hair Coulomb coefficient of dry hair (docs/model.md, "Friction
/// between hairs", for the sources).
pub const DEFAULT_HAIR_FRICTION: f32 = 0.3;

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HairHairMode {
    #[default]
    Pairwise,
    Volumetric,
}

impl HairHairSpec {
    /// The volumetric mode's settings (defaults where not given), or
    /// `None` in the pairwise mode.
    pub fn volumetric(&self) -> Option<crate::sim::Volumetric> {
        let default = crate::sim::Volumetric::default();
        (self.mode == HairHairMode::Volumetric).then(|| crate::sim::Volumetric {
            cell_size: self.cell_size.unwrap_or(default.cell_size),
            smoothing: self.smoothing.unwrap_or(default.smoothing),
            repulsion: self.repulsion.unwrap_or(default.repulsion),
            friction: self.grid_friction.unwrap_or(default.friction),
        })
    }

    /// What is wrong with the friction keys for material model `model`.
    pub fn friction_problem(&self, model: crate::sim::Model) -> Option<String> {
        let pairwise = self.mode == HairHairMode::Pairwise;
        if let Some(mu) = self.friction {
            if !pairwise {
                return Some("hair_hair friction applies to the pairwise mode (the volumetric mode has grid_friction)".into());
            }
            if model != crate::sim::Model::Physical {
                return Some("hair_hair friction applies to the physical model only".into());
            }
            if !(mu == 0.0 || (0.05..=0.5).contains(&mu)) {
                return Some(format!(
                    "hair_hair friction must be 0 (off) or a coefficient from 0.05 to 0.5, not {mu}"
                ));
            }
        }
        if self.grid_friction.is_some() && pairwise {
            return Some("hair_hair grid_friction applies to the volumetric mode (the pairwise mode has friction)".into());
        }
        None
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSpec {
    pub dt: Spanned<TimeStep>,
    /// `None`: the material model's default (`Model::default_iterations`).
    pub iterations: Option<Spanned<u32>>,
    /// The physical model's Newton tolerance, a fraction of each edge's
    /// length (`SolverParameters::tolerance`). `None`: the model's default
    /// when `iterations` is not set either, else 0 (every strand gets
    /// exactly `iterations`).
    pub tolerance: Option<Spanned<f32>>,
    /// The physical model's time integrator (`SolverParameters::integrator`);
    /// `None`: backward Euler.
    pub integrator: Option<Spanned<crate::sim::Integrator>>,
    /// Acceleration of gravity, m/s^2 (Y up).
    pub gravity: [f32; 3],
    /// Hair radius, metres (collision margin and hair-hair distance).
    pub hair_radius: Spanned<f32>,
    pub hair_hair: Option<Spanned<HairHairSpec>>,
    pub damping: Spanned<DampingSpec>,
    /// Quaternion inverse mass as `scale * w_p / l^2` (METHOD G).
    pub quaternion_mass_scale: Spanned<f32>,
    /// Sag-free start (physical model): before the first stage, solve the
    /// rest shape so the groom as authored stands still under `gravity`.
    pub sag_free: bool,
}

impl Default for SolverSpec {
    fn default() -> Self {
        SolverSpec {
            dt: Spanned::new(0..0, TimeStep::Seconds(1.0 / 360.0)),
            iterations: None,
            tolerance: None,
            integrator: None,
            gravity: [0.0, -9.8, 0.0],
            hair_radius: Spanned::new(0..0, 4.0e-5),
            hair_hair: None,
            damping: Spanned::new(
                0..0,
                DampingSpec {
                    linear: 2.0,
                    angular: 2.0,
                },
            ),
            quaternion_mass_scale: Spanned::new(0..0, 1.0),
            sag_free: true,
        }
    }
}

/// A collider shape (rapier/parry). Capsules and cylinders stand along Y.
#[derive(Debug, Clone, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// The half-space below a plane through the collider's origin.
    HalfSpace {
        normal: [f32; 3],
    },
    Cuboid {
        half_extents: [f32; 3],
    },
    Ball {
        radius: f32,
    },
    Capsule {
        half_height: f32,
        radius: f32,
    },
    Cylinder {
        half_height: f32,
        radius: f32,
    },
    /// A triangle mesh from `.obj` or `.glb`/`.gltf`, relative to the timeline.
    Mesh {
        path: String,
        #[serde(default = "one")]
        scale: f32,
    },
}

fn one() -> f32 {
    1.0
}

/// A pose at a time (global timeline seconds).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeySpec {
    pub t: f64,
    #[serde(default)]
    pub translation: [f32; 3],
    /// Rotation as X, Y, Z Euler angles in degrees, applied X first.
    #[serde(default)]
    pub rotation: [f32; 3],
}

/// When a collider takes part.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum ColliderActivity {
    /// In every stage (a head).
    #[default]
    Always,
    /// Only in the stages that list it (a pillow).
    Listed,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColliderSpec {
    pub name: Spanned<String>,
    pub shape: Spanned<ShapeSpec>,
    #[serde(default = "default_friction")]
    pub friction: Spanned<f32>,
    #[serde(default)]
    pub active: ColliderActivity,
    /// Keyframed kinematic motion; the pose is interpolated (linear
    /// translation, spherical rotation) and held before the first and after
    /// the last key. Without keys the collider stays at the origin.
    #[serde(default = "no_motion")]
    pub motion: Spanned<Vec<KeySpec>>,
}

fn no_motion() -> Spanned<Vec<KeySpec>> {
    Spanned::new(0..0, Vec::new())
}

fn default_friction() -> Spanned<f32> {
    Spanned::new(0..0, 0.3)
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum StageKind {
    Wet,
    Dry,
    Press,
    Perm,
    Wash,
    Wind,
    Settle,
    Release,
}

impl StageKind {
    pub fn name(self) -> &'static str {
        match self {
            StageKind::Wet => "wet",
            StageKind::Dry => "dry",
            StageKind::Press => "press",
            StageKind::Perm => "perm",
            StageKind::Wash => "wash",
            StageKind::Wind => "wind",
            StageKind::Settle => "settle",
            StageKind::Release => "release",
        }
    }
}

/// Drives a bond kind toward `target` over `time` seconds (linearly).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BondDriveSpec {
    pub target: f32,
    pub time: f64,
}

/// The paper's blower (19), with (21) re-forming hydrogen bonds.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlowerSpec {
    pub from: [f32; 3],
    pub to: [f32; 3],
    /// `alpha` of (19).
    pub strength: f32,
    /// The 0.003 of (21).
    #[serde(default = "default_blower_rate")]
    pub hydrogen_rate: f32,
    /// Metres: strength falls as `1 / (d / falloff_length + 1)^2` with the
    /// distance `d` from the wind's axis.
    #[serde(default = "default_falloff_length")]
    pub falloff_length: f32,
    /// Degrees; no wind outside the cone (default: none).
    #[serde(default)]
    pub cone_half_angle: Option<f32>,
    /// Speed of the blower's air on its axis, m/s: with the falloff of
    /// (19) it sets how fast the hair dries where the air reaches
    /// (`timeline::drying`). Default 10 m/s, a hand-held dryer's.
    #[serde(default)]
    pub air_speed: Option<f64>,
    /// Temperature of the blower's air on its axis, degrees Celsius.
    /// Default 60 °C, a hand-held dryer's hot setting.
    #[serde(default)]
    pub air_temperature: Option<f64>,
}

fn default_falloff_length() -> f32 {
    1.0
}

fn default_blower_rate() -> f32 {
    0.003
}

/// Perm rods: each strand is rolled from its tip toward its root onto a rod.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RodSpec {
    /// Rod radius, metres.
    pub radius: f32,
    /// Arc length left unrolled at the root, metres.
    pub root_gap: f32,
    /// Fractions of the stage: rolling ends, cutting ends, re-bonding ends
    /// (then the rods unroll and the hair is released).
    pub phases: [f64; 3],
    /// Fraction of the disulfide bonds the lotion cuts (the paper: 20 %).
    pub disulfide_cut: f32,
    /// Direction of the rods' axes; default: across each strand's tip,
    /// horizontal (along X for hair hanging straight down).
    pub axis: Option<[f32; 3]>,
}

impl Default for RodSpec {
    fn default() -> Self {
        RodSpec {
            radius: 0.01,
            root_gap: 0.02,
            phases: [0.3, 0.4, 0.8],
            disulfide_cut: 0.2,
            axis: None,
        }
    }
}

/// One step of the wind strength schedule: `v` from model frame `frame` on.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindKey {
    pub frame: u32,
    pub v: f64,
}

/// The stochastic wind of `001_*`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindSpec {
    /// Flow direction `theta_u`, degrees (azimuth from +Z toward +X).
    pub direction: f64,
    /// Strength `V` per model frame (frames counted from 1).
    pub schedule: Vec<WindKey>,
    /// Model frames per second.
    #[serde(default = "default_wind_fps")]
    pub fps: f64,
    /// The ellipsoid enclosing the head.
    pub head: crate::stochastic_wind::WindHead,
}

fn default_wind_fps() -> f64 {
    24.0
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageSpec {
    pub kind: Spanned<StageKind>,
    pub name: Option<String>,
    pub duration: Spanned<f64>,
    /// Gravity on (default) or off in this stage.
    #[serde(default = "yes")]
    pub gravity: bool,
    /// Colliders of `active = "listed"` that take part in this stage.
    #[serde(default)]
    pub colliders: Vec<Spanned<String>>,
    /// Bond drives that replace the stage kind's defaults.
    #[serde(default)]
    pub bonds: BTreeMap<String, Spanned<BondDriveSpec>>,
    /// Water content driven toward `target` over `time` (replaces the default).
    pub wetness: Option<Spanned<BondDriveSpec>>,
    /// `wet`/`wash`: shampoo also breaks the ionic bonds.
    #[serde(default)]
    pub shampoo: bool,
    /// `dry`/`wash`: time for hydrogen bonds to re-form in air (seconds).
    pub drying_time: Option<Spanned<f64>>,
    /// `dry`: a blower.
    pub blower: Option<Spanned<BlowerSpec>>,
    /// `dry` (without `drying_time`): the room air's temperature, degrees
    /// Celsius (default 20).
    pub air_temperature: Option<Spanned<f64>>,
    /// `dry` (without `drying_time`): the room air's speed past the hair,
    /// m/s (default 0: still air).
    pub air_speed: Option<Spanned<f64>>,
    /// `dry` (without `drying_time`): the room air's relative humidity,
    /// 0..1 (default 0.5).
    pub humidity: Option<Spanned<f64>>,
    /// `perm`: the rods.
    pub rod: Option<Spanned<RodSpec>>,
    /// `wind`: the stochastic wind.
    pub wind: Option<Spanned<WindSpec>>,
    /// Replaces the solver's damping in this stage.
    pub damping: Option<DampingSpec>,
    /// Replaces `[material] hold` in this stage (1/s^2; 0: off).
    pub hold: Option<Spanned<f32>>,
    /// Replaces `[material] hold_ramp` in this stage.
    pub hold_ramp: Option<Spanned<[f32; 2]>>,
}

fn yes() -> bool {
    true
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ExportWhat {
    /// Frames at `fps` over the whole timeline, streamed.
    Animated,
    /// The last pose.
    Final,
    /// The plastic rest shape (roots fixed, no gravity).
    Rest,
    /// Everything needed to continue in a later bake.
    State,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportSpec {
    /// Output file, relative to `--out` (default: the current directory).
    pub path: Spanned<String>,
    pub what: ExportWhat,
    /// Frames per second of an animated export.
    pub fps: Option<Spanned<f64>>,
    /// The program the file is for (`unreal`, `maya`, `houdini`, `blender`,
    /// `usd`): a preset of units, up axis and attribute names
    /// (`exporters::Target`); `units` and `up` override it.
    pub target: Option<Spanned<String>>,
    /// Units of the file (default: the target's, else the format's,
    /// `exporters::default_units`).
    pub units: Option<Spanned<String>>,
    /// Up axis of the file (default y).
    pub up: Option<Spanned<String>>,
    /// Resample every strand to a polyline with a point every this many
    /// metres along the smooth curve through its points.
    pub resample: Option<Spanned<f32>>,
    /// Write cubic curves: `catmull_rom` or `bspline` (default: polylines).
    pub curves: Option<Spanned<String>>,
    /// What an animated export stores per frame: `full` (every strand,
    /// the default) or `guides` (a guide cache, `super::cache`).
    pub cache: Option<Spanned<String>>,
}

/// `[groom] guides`: which strands of a dense source are simulated.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GuidesSpec {
    /// This many guides, spread over the scalp by root position.
    pub count: Option<usize>,
    /// Every K-th strand along a space-filling order of the roots.
    pub every: Option<usize>,
}

/// `[groom] render`: render strands grown between the guides.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSpec {
    /// Number of render strands.
    pub count: usize,
    /// Seed of the scattering and the noise (default: the timeline's).
    pub seed: Option<u64>,
    /// A scalp mesh (`.obj`, `.glb`) to scatter the roots on instead of the
    /// guides' root triangles, relative to the timeline, in metres.
    pub scalp: Option<String>,
    /// Pull toward the nearest guide at the tip, 0 to 1.
    #[serde(default)]
    pub clump: f32,
    /// Largest random lean at the tip, metres (0 to 0.05).
    #[serde(default)]
    pub noise: f32,
}
