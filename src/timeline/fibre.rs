//! The fibre radius a bake uses, said aloud: it sets each strand's
//! stiffness (as r^4) and weight (as r^2), and it comes silently from the
//! groom's `width` attribute when `[material] radius` is not set, where a
//! display width of a few millimetres makes fibres a hundred times too
//! thick. A radius outside real hair's range warns.

use serde::Serialize;

/// Real hair's fibre radius, metres: 10-100 um (17-181 um across; the
/// range `docs/tuning.md` documents for `[material] radius`).
pub const REAL_HAIR: std::ops::RangeInclusive<f32> = 1e-5..=1e-4;

/// The fibre radii of a bake and where they came from.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct FibreRadius {
    /// Smallest and largest radius of any vertex, metres.
    pub min: f32,
    pub max: f32,
    /// `[material] radius`, `the groom's width / 2` or `the default`.
    pub source: String,
}

/// The radii of `strands`, built from `groom` with `timeline`'s material.
pub fn fibre_radius(
    timeline: &super::Timeline,
    groom: &groom::Groom,
    radii: &[f32],
) -> FibreRadius {
    let (min, max) = radii.iter().fold((f32::INFINITY, 0.0f32), |(lo, hi), &r| {
        (lo.min(r), hi.max(r))
    });
    let min = if min.is_finite() { min } else { 0.0 };
    // As the strands read it (`sim::state`): a width under 2 cm is taken.
    let usable_width = ["width", "widths", "groom_width"].iter().any(|name| {
        matches!(
            groom.attribute(name).map(|a| &a.values),
            Some(groom::AttributeValues::Float(v))
                if v.iter().any(|w| w.is_finite() && *w > 0.0 && *w < 0.02)
        )
    });
    let source = if timeline.file.material.radius.is_some() {
        "[material] radius"
    } else if usable_width {
        "the groom's width / 2"
    } else {
        "the default"
    };
    FibreRadius {
        min,
        max,
        source: source.into(),
    }
}

/// Metres as micrometres or millimetres, whichever reads better.
fn length(metres: f32) -> String {
    if metres < 1e-5 {
        format!("{:.2} um", metres * 1e6)
    } else if metres < 1e-3 {
        format!("{:.0} um", metres * 1e6)
    } else {
        format!("{:.1} mm", metres * 1e3)
    }
}

impl FibreRadius {
    /// `40 um (the default)`, `2.0 mm - 3.0 mm (the groom's width / 2)`.
    pub fn describe(&self) -> String {
        let range = if self.min == self.max {
            length(self.min)
        } else {
            format!("{} - {}", length(self.min), length(self.max))
        };
        format!("{range} ({})", self.source)
    }

    /// A warning when some radius lies outside real hair's.
    pub fn warning(&self) -> Option<String> {
        if REAL_HAIR.contains(&self.min) && REAL_HAIR.contains(&self.max) {
            return None;
        }
        let remedy = if self.source == "the groom's width / 2" {
            "the groom's width is probably a display width: set [material] radius = 4e-5 (or the hair's own) to simulate real fibres"
        } else {
            "set [material] radius within 1e-5 - 1e-4 m unless this hair is meant to be unlike real hair"
        };
        Some(format!(
            "fibre radius {}: outside real hair's {} - {} (bending stiffness goes as r^4, weight as r^2); {remedy}",
            self.describe(),
            length(*REAL_HAIR.start()),
            length(*REAL_HAIR.end())
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radii_outside_real_hair_warn() {
        let of = |min, max, source: &str| FibreRadius {
            min,
            max,
            source: source.into(),
        };
        assert_eq!(
            of(4e-5, 4e-5, "the default").describe(),
            "40 um (the default)"
        );
        assert_eq!(of(4e-5, 4e-5, "the default").warning(), None);
        let display = of(2e-3, 2e-3, "the groom's width / 2").warning().unwrap();
        assert!(
            display.starts_with(
                "fibre radius 2.0 mm (the groom's width / 2): outside real hair's 10 um - 100 um"
            ) && display.contains("set [material] radius = 4e-5"),
            "{display}"
        );
        assert!(of(5e-6, 4e-5, "[material] radius").warning().is_some());
    }
}
