//! Length units and up axes.
//!
//! The units rule, applied by every importer and exporter:
//! - A reader takes the units the file records: USD's `metersPerUnit`, glTF's
//!   metres, the mark groombake leaves in the `.obj` header comment and in
//!   Alembic archive metadata (`groombake_units`).
//! - Where the file records none: the units the user states
//!   (`--source-units`, `[groom] units`); else, for Alembic, the writing
//!   application (`_ai_Application`: Blender and Houdini work in metres, Maya,
//!   Unreal and anything else in centimetres); else the format's convention,
//!   centimetres for `.hair`, `.data` and `.obj`.
//! - A writer writes the units it is asked for (`convert --units`,
//!   `[[export]] units`); by default glTF in metres (its specification), USD in
//!   the groom's units (it records them), and `.abc`, `.hair`, `.data`, `.obj`
//!   in centimetres, the convention their readers assume.

use std::fmt;
use std::str::FromStr;

/// The Alembic archive metadata key where groombake records the units it
/// wrote in (Alembic has no unit field of its own).
pub const ALEMBIC_UNITS_KEY: &str = "groombake_units";

/// A length unit, as metres per unit (USD's `metersPerUnit`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Units {
    pub meters_per_unit: f64,
}

impl Units {
    pub const METERS: Units = Units {
        meters_per_unit: 1.0,
    };
    pub const CENTIMETERS: Units = Units {
        meters_per_unit: 0.01,
    };
    pub const MILLIMETERS: Units = Units {
        meters_per_unit: 0.001,
    };
    pub const INCHES: Units = Units {
        meters_per_unit: 0.0254,
    };

    /// The conventional name (`m`, `cm`, `mm`, `in`) or the number of metres.
    pub fn name(self) -> String {
        for (name, units) in Self::NAMED {
            if units.meters_per_unit == self.meters_per_unit {
                return name.to_string();
            }
        }
        format!("{}", self.meters_per_unit)
    }

    const NAMED: [(&'static str, Units); 4] = [
        ("m", Units::METERS),
        ("cm", Units::CENTIMETERS),
        ("mm", Units::MILLIMETERS),
        ("in", Units::INCHES),
    ];
}

impl Default for Units {
    /// Formats that carry no units (`.hair`, Alembic, `.obj`) are taken as
    /// centimetres, as groom tools write them.
    fn default() -> Self {
        Units::CENTIMETERS
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

impl FromStr for Units {
    type Err = String;

    /// `m`, `cm`, `mm`, `in`, or a positive number of metres per unit.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.trim().to_ascii_lowercase();
        for (name, units) in Self::NAMED {
            if lower == name {
                return Ok(units);
            }
        }
        match lower.as_str() {
            "meter" | "meters" | "metre" | "metres" => return Ok(Units::METERS),
            "centimeter" | "centimeters" | "centimetre" | "centimetres" => {
                return Ok(Units::CENTIMETERS)
            }
            "millimeter" | "millimeters" | "millimetre" | "millimetres" => {
                return Ok(Units::MILLIMETERS)
            }
            "inch" | "inches" => return Ok(Units::INCHES),
            _ => {}
        }
        // A scale outside this range turns a groom's f32 coordinates into
        // infinities or zeros (a 10 cm hair at 1e300 m per unit).
        const RANGE: std::ops::RangeInclusive<f64> = 1e-6..=1e6;
        match lower.parse::<f64>() {
            Ok(m) if RANGE.contains(&m) => Ok(Units { meters_per_unit: m }),
            Ok(m) if m.is_finite() && m > 0.0 => Err(format!(
                "units {:?}: metres per unit must be between 1e-6 and 1e6",
                s.escape_debug().to_string()
            )),
            _ => Err(format!(
                "unknown units {:?} (expected m, cm, mm, in, or metres per unit)",
                s.escape_debug().to_string()
            )),
        }
    }
}

/// The axis that points up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum UpAxis {
    #[default]
    Y,
    Z,
}

impl UpAxis {
    /// Maps a point of this axis convention to Y-up (right-handed both ways:
    /// Z-up `(x, y, z)` is Y-up `(x, z, -y)`).
    pub fn to_y_up(self, p: [f32; 3]) -> [f32; 3] {
        match self {
            UpAxis::Y => p,
            UpAxis::Z => [p[0], p[2], -p[1]],
        }
    }

    /// Maps a Y-up point to this axis convention.
    pub fn from_y_up(self, p: [f32; 3]) -> [f32; 3] {
        match self {
            UpAxis::Y => p,
            UpAxis::Z => [p[0], -p[2], p[1]],
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            UpAxis::Y => "Y",
            UpAxis::Z => "Z",
        }
    }
}

impl fmt::Display for UpAxis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for UpAxis {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "y" | "Y" => Ok(UpAxis::Y),
            "z" | "Z" => Ok(UpAxis::Z),
            _ => Err(format!("unknown up axis '{s}' (expected y or z)")),
        }
    }
}

/// Attributes whose values are lengths and so scale with the unit.
pub(crate) fn is_length_attribute(name: &str) -> bool {
    matches!(name, "width" | "widths" | "groom_width" | "thickness")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_units() {
        assert_eq!("cm".parse::<Units>().unwrap(), Units::CENTIMETERS);
        assert_eq!("0.5".parse::<Units>().unwrap().meters_per_unit, 0.5);
        assert!("-1".parse::<Units>().is_err());
        assert!("furlong".parse::<Units>().is_err());
        assert!("1e-300".parse::<Units>().is_err());
        assert!("1e300".parse::<Units>().is_err());
        assert_eq!(Units::CENTIMETERS.to_string(), "cm");
    }

    #[test]
    fn up_axis_round_trip() {
        let p = [1.0, 2.0, 3.0];
        assert_eq!(UpAxis::Z.from_y_up(UpAxis::Z.to_y_up(p)), p);
    }
}
