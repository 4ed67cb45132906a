//! Guides and render hair in a bake: where the render strands come from
//! (`[groom]` `guides` and `render`), and how each export and the sheet
//! deliver them (interpolated from the simulated guides, then reshaped by
//! the export's `resample` or `curves`).
//!
//! The solver simulates the guides only. Every delivered pose (each
//! animated frame, the final, rest and state exports, the sheet's
//! pictures) interpolates the render strands from the guides of that pose,
//! one pose at a time, so memory does not grow with the frame count.

use super::error::BakeError;
use super::schema::{ExportSpec, ExportWhat};
pub use super::schema::{GuidesSpec, RenderSpec};
use super::{Timeline, TimelineError};
use groom::curves::{CurveForm, CurveMap};
use groom::guides::{GROOM_CLOSEST_GUIDES, GROOM_GUIDE, GROOM_GUIDE_WEIGHTS, GROOM_ID};
use groom::interpolate::{InterpolationOptions, RenderHair};
use groom::{AttributeValues, CurveBasis, Groom, Scope};

/// The most render strands a timeline may ask for.
pub const MAX_RENDER_STRANDS: usize = 2_000_000;

/// Checks `[groom] guides` and `render` (before any work).
pub fn check_groom(timeline: &Timeline) -> Result<(), TimelineError> {
    let spec = &timeline.file.groom;
    if let Some(guides) = &spec.guides {
        let g = guides.get_ref();
        match (g.count, g.every) {
            (Some(n), None) if n >= 1 => {}
            (None, Some(k)) if k >= 1 => {}
            _ => {
                return Err(timeline.error_at(
                    guides.span(),
                    "guides takes either `count = N` or `every = K` (N, K >= 1)",
                ))
            }
        }
    }
    if let Some(render) = &spec.render {
        let r = render.get_ref();
        if r.count == 0 || r.count > MAX_RENDER_STRANDS {
            return Err(timeline.error_at(
                render.span(),
                format!("render count must be 1 to {MAX_RENDER_STRANDS}"),
            ));
        }
        if !(0.0..=1.0).contains(&r.clump) {
            return Err(timeline.error_at(render.span(), "render clump must be in [0, 1]"));
        }
        if !(0.0..=0.05).contains(&r.noise) {
            return Err(
                timeline.error_at(render.span(), "render noise must be in [0, 0.05] metres")
            );
        }
        if let Some(scalp) = &r.scalp {
            let path = timeline.resolve(scalp);
            if let Err(message) = super::check_input_file(&path, "scalp mesh") {
                return Err(timeline.error_at(render.span(), message));
            }
        }
    }
    Ok(())
}

/// The shorter and longer segment lengths `resample` accepts, metres.
const RESAMPLE_RANGE: std::ops::RangeInclusive<f32> = 0.0005..=0.5;

/// The curve form an export asks for (checked by [`check_export`]).
pub fn curve_form(e: &ExportSpec) -> CurveForm {
    if let Some(segment) = &e.resample {
        return CurveForm::Resampled {
            segment: *segment.get_ref(),
        };
    }
    match e.curves.as_ref().map(|c| c.get_ref().as_str()) {
        Some("catmull_rom") => CurveForm::Cubic(CurveBasis::CatmullRom),
        Some("bspline") => CurveForm::Cubic(CurveBasis::Bspline),
        _ => CurveForm::Polyline,
    }
}

/// Checks an export's `resample` and `curves`.
pub fn check_export(timeline: &Timeline, e: &ExportSpec) -> Result<(), TimelineError> {
    let reshaped = e
        .resample
        .as_ref()
        .map(|r| r.span())
        .or(e.curves.as_ref().map(|c| c.span()));
    if let (Some(_), Some(c)) = (&e.resample, &e.curves) {
        return Err(timeline.error_at(c.span(), "give either `resample` or `curves`, not both"));
    }
    if let Some(r) = &e.resample {
        if !RESAMPLE_RANGE.contains(r.get_ref()) {
            return Err(timeline.error_at(
                r.span(),
                format!(
                    "resample is a segment length in metres, {} to {}",
                    RESAMPLE_RANGE.start(),
                    RESAMPLE_RANGE.end()
                ),
            ));
        }
    }
    if let Some(c) = &e.curves {
        if !matches!(c.get_ref().as_str(), "linear" | "catmull_rom" | "bspline") {
            return Err(timeline.error_at(
                c.span(),
                "curves must be \"linear\", \"catmull_rom\" or \"bspline\"",
            ));
        }
    }
    if let Some(c) = &e.curves {
        let extension = importers::extension_of(std::path::Path::new(e.path.get_ref()));
        let cubic = c.get_ref() != "linear";
        if cubic && !matches!(extension.as_str(), "usda" | "usdc" | "usd" | "abc") {
            return Err(timeline.error_at(
                c.span(),
                format!("'.{extension}' holds polylines only: use `resample` (cubic curves go to USD and Alembic)"),
            ));
        }
    }
    if let (Some(span), ExportWhat::State) = (reshaped, e.what) {
        return Err(timeline.error_at(
            span,
            "a state export keeps the simulated points: no resample or curves",
        ));
    }
    Ok(())
}

/// The Unreal attributes a source's split leaves on the guides; the bake
/// sets them again on every delivered groom.
const SPLIT_ATTRIBUTES: [&str; 4] = [
    GROOM_GUIDE,
    GROOM_ID,
    GROOM_CLOSEST_GUIDES,
    GROOM_GUIDE_WEIGHTS,
];

fn strip_split(mut groom: Groom) -> Groom {
    for name in SPLIT_ATTRIBUTES {
        groom.remove_attribute(name);
    }
    groom
}

/// The guides to simulate and the render hair that follows them, from the
/// loaded groom (metres, Y up) and the timeline's `[groom]`.
pub fn split_or_grow(
    timeline: &Timeline,
    groom: Groom,
    seed: u64,
) -> Result<(Groom, Option<RenderHair>), BakeError> {
    let spec = &timeline.file.groom;
    let options = |seed: u64| {
        let r = spec.render.as_ref().map(|r| r.get_ref());
        InterpolationOptions {
            clump: r.map_or(0.0, |r| r.clump),
            noise: r.map_or(0.0, |r| r.noise),
            seed,
        }
    };
    let (guides, mut hair) =
        if let Some(split) = groom.split_guides().filter(|_| groom.has_render_split()) {
            let guides = strip_split(split.guides);
            let hair = from_source_links(
                &groom,
                &split.guide_indices,
                &split.render,
                &guides,
                options(seed),
            );
            (guides, Some(hair))
        } else if let Some(pick) = &spec.guides {
            let roots = groom::guides::roots(&groom);
            let picked = match (pick.get_ref().count, pick.get_ref().every) {
                (Some(n), _) => groom::guides::pick_spread(&roots, n),
                (_, every) => groom::guides::pick_every(&roots, every.unwrap_or(1)),
            };
            let mut is_guide = vec![false; groom.strand_count()];
            for &i in &picked {
                is_guide[i] = true;
            }
            let others: Vec<usize> = (0..groom.strand_count())
                .filter(|&i| !is_guide[i])
                .collect();
            let guides = strip_split(groom.subset(&picked));
            let render = groom.subset(&others);
            let hair = RenderHair::nearest(
                &guides,
                &groom::guides::roots(&render),
                render.strand_vertex_counts.clone(),
                options(seed),
            )
            .with_detail(&guides, &render.points);
            (guides, (render.strand_count() > 0).then_some(hair))
        } else {
            (groom, None)
        };
    if let Some(render) = &spec.render {
        let r = render.get_ref();
        let seed = r.seed.unwrap_or(seed);
        hair = Some(match &r.scalp {
            None => RenderHair::grow(&guides, r.count, options(seed)),
            Some(scalp) => on_scalp(timeline, &guides, scalp, r.count, options(seed))?,
        });
    }
    Ok((guides, hair))
}

/// Render hair of a source that holds both kinds: the links it gives
/// (`groom_closest_guides` as guide ids, `groom_guide_weights`), or the
/// three nearest guides when it gives none; the strands keep their shape.
fn from_source_links(
    source: &Groom,
    guide_indices: &[usize],
    render: &Groom,
    guides: &Groom,
    options: InterpolationOptions,
) -> RenderHair {
    let roots = groom::guides::roots(render);
    let counts = render.strand_vertex_counts.clone();
    // Guide ids (groom_id of the guides, or their order) to guide indices.
    let ids: Vec<i64> = match source.attribute(GROOM_ID).map(|a| &a.values) {
        Some(AttributeValues::Int(v)) if v.len() == source.strand_count() => {
            guide_indices.iter().map(|&i| i64::from(v[i])).collect()
        }
        _ => (0..guide_indices.len() as i64).collect(),
    };
    let index_of = |id: f32| ids.iter().position(|&x| x as f32 == id).map(|i| i as u32);
    let vec3 = |name: &str| match render.attribute(name) {
        Some(a) if a.scope == Scope::Strand => match &a.values {
            AttributeValues::Vec3(v) if v.len() == render.strand_count() => Some(v.clone()),
            _ => None,
        },
        _ => None,
    };
    let links = vec3(GROOM_CLOSEST_GUIDES)
        .zip(vec3(GROOM_GUIDE_WEIGHTS))
        .and_then(|(c, w)| {
            let closest: Option<Vec<[u32; 3]>> = c
                .iter()
                .map(|c| Some([index_of(c[0])?, index_of(c[1])?, index_of(c[2])?]))
                .collect();
            let weights_ok = w.iter().all(|w| {
                let sum: f32 = w.iter().sum();
                w.iter().all(|x| x.is_finite() && *x >= 0.0) && (sum - 1.0).abs() < 1e-3
            });
            closest.filter(|_| weights_ok).map(|c| (c, w))
        });
    let hair = match links {
        Some((closest, weights)) => {
            RenderHair::linked(guides, &roots, closest, weights, counts, options)
        }
        None => RenderHair::nearest(guides, &roots, counts, options),
    };
    hair.with_detail(guides, &render.points)
}

/// Render roots scattered on a scalp mesh (uniform by area), following
/// their three nearest guides; with the mesh's UVs, each root's `root_uv`
/// blends its triangle's corner UVs as its position does.
fn on_scalp(
    timeline: &Timeline,
    guides: &Groom,
    scalp: &str,
    count: usize,
    options: InterpolationOptions,
) -> Result<RenderHair, BakeError> {
    let path = timeline.resolve(scalp);
    let importers::mesh::Mesh {
        vertices,
        triangles,
        corner_uvs,
    } = importers::mesh::read_mesh(&path)?;
    let corner = |t: &[u32; 3], k: usize| vertices.get(t[k] as usize).copied();
    let mut cumulative = Vec::with_capacity(triangles.len());
    let mut total = 0.0f64;
    for t in &triangles {
        let (Some(a), Some(b), Some(c)) = (corner(t, 0), corner(t, 1), corner(t, 2)) else {
            return Err(BakeError::Input {
                file: path,
                message: "a triangle refers to a missing vertex".into(),
            });
        };
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        total += 0.5 * f64::from(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        cumulative.push(total);
    }
    if total.is_nan() || total <= 0.0 {
        return Err(BakeError::Input {
            file: path,
            message: "the scalp mesh has no area".into(),
        });
    }
    let mut state = options.seed ^ 0x0073_6361_6c70;
    let mut unit = move || {
        // SplitMix64 (a fixed stream on every platform).
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut roots = Vec::with_capacity(count);
    let mut root_uvs = Vec::with_capacity(if corner_uvs.is_some() { count } else { 0 });
    for _ in 0..count {
        let at = unit() * total;
        let i = cumulative
            .partition_point(|&c| c < at)
            .min(triangles.len() - 1);
        let t = &triangles[i];
        let (a, b, c) = (
            vertices[t[0] as usize],
            vertices[t[1] as usize],
            vertices[t[2] as usize],
        );
        let (r1, r2) = (unit().sqrt() as f32, unit() as f32);
        let w = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
        roots.push(std::array::from_fn(|k| {
            w[0] * a[k] + w[1] * b[k] + w[2] * c[k]
        }));
        if let Some([a, b, c]) = corner_uvs.as_ref().and_then(|uvs| uvs.get(i)) {
            root_uvs.push(std::array::from_fn(|k| {
                w[0] * a[k] + w[1] * b[k] + w[2] * c[k]
            }));
        }
    }
    let guide_roots = groom::guides::roots(guides);
    // Each render strand takes the vertex count of its nearest guide.
    let counts = roots
        .iter()
        .map(|r: &[f32; 3]| {
            let nearest = guide_roots
                .iter()
                .enumerate()
                .min_by(|a, b| distance2(*a.1, *r).total_cmp(&distance2(*b.1, *r)))
                .map_or(0, |(i, _)| i);
            guides
                .strand_vertex_counts
                .get(nearest)
                .copied()
                .unwrap_or(2)
        })
        .collect();
    let hair = RenderHair::nearest(guides, &roots, counts, options);
    Ok(match corner_uvs {
        Some(_) => hair.with_root_uvs(root_uvs),
        None => hair,
    })
}

fn distance2(a: [f32; 3], b: [f32; 3]) -> f32 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

/// One pose of the guides delivered as a static output: with the render
/// hair, in the curve form (built from this pose).
pub fn deliver(hair: Option<&RenderHair>, guides: &Groom, form: CurveForm) -> Groom {
    let joined = match hair {
        Some(h) => h.joined(guides),
        None => guides.clone(),
    };
    match form {
        CurveForm::Polyline => joined,
        form => CurveMap::new(&joined, form).apply(&joined),
    }
}

/// How one output delivers the simulated guides: with the render hair
/// and in the output's curve form. Built from the first pose it delivers;
/// the render hair is handed to each call (the bake owns it).
pub struct Delivery {
    map: Option<CurveMap>,
    guide_counts: Vec<u32>,
}

impl Delivery {
    pub fn new(hair: Option<&RenderHair>, guides: &Groom, form: CurveForm) -> Delivery {
        let map = (form != CurveForm::Polyline).then(|| {
            let joined = match hair {
                Some(h) => h.joined(guides),
                None => guides.clone(),
            };
            CurveMap::new(&joined, form)
        });
        Delivery {
            map,
            guide_counts: guides.strand_vertex_counts.clone(),
        }
    }

    /// The delivered groom of a pose of the guides (with their attributes).
    pub fn groom(&self, hair: Option<&RenderHair>, guides: &Groom) -> Groom {
        let joined = match hair {
            Some(h) => h.joined(guides),
            None => guides.clone(),
        };
        match &self.map {
            Some(map) => map.apply(&joined),
            None => joined,
        }
    }

    /// The delivered points of a pose of the guides.
    pub fn points(&self, hair: Option<&RenderHair>, guide_points: &[[f32; 3]]) -> Vec<[f32; 3]> {
        let joined = match hair {
            Some(h) => h.joined_points(&self.guide_counts, guide_points),
            None => guide_points.to_vec(),
        };
        match &self.map {
            Some(map) => map.points(&joined),
            None => joined,
        }
    }
}
