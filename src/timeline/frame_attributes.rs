//! The attributes a bake changes over time, written per frame in animated
//! exports (`groom::Frame::attributes`): the bond rates the timeline's
//! stages drive and the wetness, when any stage wets or dries the hair.
//! Attributes no stage changes stay the groom's, written once.

use super::stages::StagePlan;
use super::Timeline;
use crate::sim::attribute_names::{BOND_RATES, WETNESS};
use groom::interpolate::RenderHair;
use groom::{Attribute, Groom};

/// The attributes the timeline's stages change, in a fixed order (bond
/// rates, then wetness).
pub fn changing(plans: &[StagePlan]) -> Vec<&'static str> {
    let mut names = Vec::new();
    for (kind, name) in BOND_RATES.iter().enumerate() {
        // Hydrogen bonds also re-form under a blower (21) and as the hair
        // dries by evaporation.
        let driven = plans.iter().any(|p| {
            !p.bonds[kind].is_empty() || (kind == 0 && (p.blower.is_some() || p.drying.is_some()))
        });
        if driven {
            names.push(*name);
        }
    }
    if plans
        .iter()
        .any(|p| !p.wetness.is_empty() || p.drying.is_some())
    {
        names.push(WETNESS);
    }
    names
}

/// [`changing`] of a timeline's stages.
pub fn changing_in(timeline: &Timeline) -> Vec<&'static str> {
    let plans: Vec<StagePlan> = timeline
        .file
        .stages
        .get_ref()
        .iter()
        .map(StagePlan::new)
        .collect();
    changing(&plans)
}

/// The values of `names` on the delivered groom of the guides' pose
/// `guides` (render hair interpolated, the export's curve form).
pub fn delivered(
    delivery: &super::render::Delivery,
    render: Option<&RenderHair>,
    guides: &Groom,
    names: &[&str],
) -> Vec<Attribute> {
    let groom = delivery.groom(render, guides);
    names
        .iter()
        .filter_map(|name| groom.attribute(name).cloned())
        .collect()
}

/// The values of `names` on the guides alone (a guide cache's frames).
pub fn of_guides(guides: &Groom, names: &[&str]) -> Vec<Attribute> {
    names
        .iter()
        .filter_map(|name| guides.attribute(name).cloned())
        .collect()
}
