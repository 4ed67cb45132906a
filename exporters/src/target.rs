//! Destinations: the program a file is written for, as a preset of length
//! units, up axis and attribute names (`[[export]] target`, `convert
//! --target`). `docs/formats.md` ("Units and up axis") gives the sources of
//! each preset.
//!
//! Alembic, `.obj`, `.hair` and `.data` record no up axis: every reader of
//! them assumes Y up (Blender's and Unreal's importers rotate Y-up files into
//! their Z-up scenes), so a preset's up axis applies only to USD, which
//! records it (`upAxis`). Alembic and `.obj` record no units either (groombake
//! marks its own); a preset picks the units its program reads them in.

use crate::extension_of;
use groom::{Units, UpAxis};
use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// A program a file is written for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// Unreal Engine's groom importer: centimetres, Y up in Alembic, the
    /// `groom_*` attributes of its Alembic groom schema.
    Unreal,
    /// Maya: centimetres (its default working unit), Y up.
    Maya,
    /// Houdini: metres, Y up.
    Houdini,
    /// Blender: metres; USD written Z up (Blender's scene axis).
    Blender,
    /// A USD pipeline: metres, Y up (USD's fallback axis), recorded in the
    /// layer.
    Usd,
}

/// Which names the Alembic writer gives attributes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AttributeSet {
    /// Every attribute under its own name, plus the Unreal groom attributes
    /// (`groom_version_*`, `groom_guide`, `groom_group_id`, `groom_width`,
    /// `groom_root_uv`) that Unreal's importer reads.
    #[default]
    WithUnreal,
    /// Every attribute under its own name only.
    Plain,
}

/// What a file is written as: units, up axis and attribute names.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Destination {
    pub units: Units,
    pub up: UpAxis,
    pub attributes: AttributeSet,
}

impl Target {
    pub const ALL: [Target; 5] = [
        Target::Unreal,
        Target::Maya,
        Target::Houdini,
        Target::Blender,
        Target::Usd,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Target::Unreal => "unreal",
            Target::Maya => "maya",
            Target::Houdini => "houdini",
            Target::Blender => "blender",
            Target::Usd => "usd",
        }
    }

    /// The length units the program reads a file at `path` in.
    pub fn units(self, path: &Path) -> Units {
        match extension_of(path).as_str() {
            // glTF is metres by its specification, whoever reads it.
            "gltf" | "glb" => Units::METERS,
            _ => match self {
                Target::Unreal | Target::Maya => Units::CENTIMETERS,
                Target::Houdini | Target::Blender | Target::Usd => Units::METERS,
            },
        }
    }

    /// The up axis a file at `path` is written with for the program.
    pub fn up(self, path: &Path) -> UpAxis {
        match (extension_of(path).as_str(), self) {
            ("usda" | "usdc" | "usd", Target::Blender) => UpAxis::Z,
            _ => UpAxis::Y,
        }
    }

    pub fn attributes(self) -> AttributeSet {
        match self {
            Target::Unreal => AttributeSet::WithUnreal,
            _ => AttributeSet::Plain,
        }
    }
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Target {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.trim().to_ascii_lowercase();
        Target::ALL
            .into_iter()
            .find(|t| t.name() == lower)
            .ok_or_else(|| {
                format!(
                    "unknown target {:?} (expected {})",
                    s.escape_debug().to_string(),
                    Target::ALL.map(Target::name).join(", ")
                )
            })
    }
}

/// What a file at `path` is written as: the explicit `units`/`up` first,
/// then the target's preset, then the format's default
/// ([`crate::default_units`]; Y up except USD, which keeps the groom's axis).
pub fn destination(
    path: &Path,
    target: Option<Target>,
    units: Option<Units>,
    up: Option<UpAxis>,
    groom_units: Units,
    groom_up: UpAxis,
) -> Destination {
    let default_up = match extension_of(path).as_str() {
        "usda" | "usdc" | "usd" => groom_up,
        _ => UpAxis::Y,
    };
    Destination {
        units: units
            .or(target.map(|t| t.units(path)))
            .unwrap_or_else(|| crate::default_units(path, groom_units)),
        up: up.or(target.map(|t| t.up(path))).unwrap_or(default_up),
        attributes: target.map_or(AttributeSet::default(), Target::attributes),
    }
}

/// What the numbers of a file that records neither units nor up axis for
/// other programs (Alembic, `.obj`) are, as a bake and convert print it
/// (`"m, Y up"`). `None` for the formats that record them (USD, glTF) or
/// whose units have their own warning (`.hair`, `.data`).
pub fn written_in(path: &Path, units: Units, up: UpAxis) -> Option<String> {
    match extension_of(path).as_str() {
        // The Alembic writer turns every groom to Y up.
        "abc" => Some(format!("{units}, Y up")),
        "obj" => Some(format!("{units}, {up} up")),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets() {
        let abc = Path::new("a.abc");
        let usd = Path::new("a.usda");
        assert_eq!(Target::Unreal.units(abc), Units::CENTIMETERS);
        assert_eq!(Target::Blender.units(abc), Units::METERS);
        assert_eq!(Target::Blender.up(abc), UpAxis::Y);
        assert_eq!(Target::Blender.up(usd), UpAxis::Z);
        assert_eq!(Target::Maya.units(Path::new("a.glb")), Units::METERS);
        assert_eq!("Houdini".parse::<Target>(), Ok(Target::Houdini));
        assert!("nuke".parse::<Target>().unwrap_err().contains("unreal"));
    }

    #[test]
    fn explicit_units_win_over_the_preset() {
        let d = destination(
            Path::new("a.abc"),
            Some(Target::Unreal),
            Some(Units::MILLIMETERS),
            None,
            Units::METERS,
            UpAxis::Z,
        );
        assert_eq!(d.units, Units::MILLIMETERS);
        assert_eq!(d.up, UpAxis::Y);
        assert_eq!(d.attributes, AttributeSet::WithUnreal);
        let default = destination(
            Path::new("a.abc"),
            None,
            None,
            None,
            Units::CENTIMETERS,
            UpAxis::Z,
        );
        assert_eq!(default.units, Units::METERS);
        assert_eq!(default.up, UpAxis::Y);
    }
}
