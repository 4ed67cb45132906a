//! `groombake inspect FILE [--json]`: a groom's facts, or a collider
//! mesh's (`.obj`, `.glb`, `.gltf` with triangles and no curves): its
//! triangles and bounds, to place it against the groom.

use clap::Args;
use groom::Groom;
use serde_json::json;
use std::io::Write;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The groom file, or a collider mesh (.obj, .glb, .gltf).
    #[arg(value_hint = clap::ValueHint::FilePath)]
    file: PathBuf,
    /// Print a JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// The facts `inspect` prints, as JSON.
pub fn summary(groom: &Groom) -> serde_json::Value {
    let (min, max) = groom.bounds().unwrap_or(([0.0; 3], [0.0; 3]));
    let problems = groom.validate();
    let single_point = problems
        .iter()
        .filter(|p| matches!(p.kind, groom::ProblemKind::SinglePointStrand))
        .count();
    let attributes: Vec<_> = groom
        .attributes
        .iter()
        .map(|a| {
            json!({
                "name": a.name,
                "scope": a.scope,
                "type": a.values.type_name(),
                "count": a.values.len(),
            })
        })
        .collect();
    let times: Vec<f64> = groom.frames.iter().map(|f| f.time).collect();
    let prims: Vec<_> = prims_of(groom)
        .map(|(path, strands)| json!({"path": path, "strands": strands}))
        .collect();
    json!({
        "file": groom.provenance.source.as_ref().map(|p| p.display().to_string()),
        "format": groom.provenance.format,
        "info": groom.provenance.info,
        "strands": groom.strand_count(),
        "vertices": groom.vertex_count(),
        "single_point_strands": single_point,
        "bounds": { "min": min, "max": max },
        "units": groom.units.name(),
        "meters_per_unit": groom.units.meters_per_unit,
        "units_source": groom.provenance.units_source,
        "up_axis": groom.up_axis.name(),
        "basis": groom.basis.name(),
        "frames": groom.frames.len(),
        "frame_times": times,
        "attributes": attributes,
        "prims": prims,
        "first_point": groom.points.first(),
    })
}

/// The curves objects the reader lists (`groom::PRIMS_KEY`): path and
/// strand count.
fn prims_of(groom: &Groom) -> impl Iterator<Item = (&str, usize)> {
    groom
        .provenance
        .metadata
        .get(groom::PRIMS_KEY)
        .map(String::as_str)
        .unwrap_or("")
        .lines()
        .filter_map(|line| {
            let (path, count) = line.rsplit_once(' ')?;
            Some((path, count.parse().ok()?))
        })
}

/// Which rule of the units rule (README, "Units") gave the units, in words.
fn units_rule(source: &str) -> String {
    match source {
        "file" => "recorded in the file".into(),
        "format" => "the format's convention (it records no units; --source-units overrides)".into(),
        "stated" => "as stated".into(),
        other => match other.strip_prefix("application ") {
            Some(application) => format!(
                "from the writing application '{application}' (Alembic records no units; --source-units overrides)"
            ),
            None => other.into(),
        },
    }
}

/// Each stretch of time with one topology: from when, strands, vertices
/// and frames (one entry for a file whose topology does not change).
fn topology(grooms: &[Groom]) -> Vec<serde_json::Value> {
    grooms
        .iter()
        .map(|g| {
            json!({
                "from_time": g.frames.first().map(|f| f.time),
                "strands": g.strand_count(),
                "vertices": g.vertex_count(),
                "frames": g.frames.len(),
            })
        })
        .collect()
}

/// A mesh file as a collider reads it: `None` when it is no mesh (then
/// the groom reader's error stands).
fn mesh_of(path: &std::path::Path) -> Option<importers::mesh::Mesh> {
    let extension = importers::extension_of(path);
    if !matches!(extension.as_str(), "obj" | "glb" | "gltf") {
        return None;
    }
    importers::mesh::read_mesh(path).ok()
}

/// Prints a collider mesh's triangles and bounds (metres, as a collider
/// reads it, before its `scale`).
fn inspect_mesh(args: &InspectArgs, mesh: &importers::mesh::Mesh) -> anyhow::Result<()> {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for v in &mesh.vertices {
        for k in 0..3 {
            min[k] = min[k].min(v[k]);
            max[k] = max[k].max(v[k]);
        }
    }
    let size: Vec<f32> = (0..3).map(|k| max[k] - min[k]).collect();
    let mut out = std::io::stdout().lock();
    if args.json {
        let summary = json!({
            "kind": "mesh",
            "format": importers::extension_of(&args.file),
            "triangles": mesh.triangles.len(),
            "vertices": mesh.vertices.len(),
            "bounds": {"min": min, "max": max},
            "size": size,
            "units": "m",
            "uvs": mesh.corner_uvs.is_some(),
        });
        serde_json::to_writer_pretty(&mut out, &summary)?;
        writeln!(out)?;
        return Ok(());
    }
    writeln!(out, "file        {}", args.file.display())?;
    writeln!(
        out,
        "format      mesh ({}): a collider, no curves",
        importers::extension_of(&args.file)
    )?;
    writeln!(out, "triangles   {}", mesh.triangles.len())?;
    writeln!(out, "vertices    {}", mesh.vertices.len())?;
    writeln!(out, "bounds      {min:?} .. {max:?}")?;
    writeln!(
        out,
        "size        {:.4} x {:.4} x {:.4} m (as a collider reads it, times its `scale`)",
        size[0], size[1], size[2]
    )?;
    writeln!(
        out,
        "uvs         {}",
        if mesh.corner_uvs.is_some() {
            "yes"
        } else {
            "no"
        }
    )?;
    Ok(())
}

pub fn run(args: InspectArgs) -> anyhow::Result<()> {
    let grooms = match super::read_sequence(&args.file) {
        Ok(grooms) => grooms,
        Err(error) => match mesh_of(&args.file) {
            Some(mesh) => return inspect_mesh(&args, &mesh),
            None => return Err(error),
        },
    };
    let groom = &grooms[0];
    let mut summary = summary(groom);
    summary["topology"] = json!(topology(&grooms));
    let losses = super::losses(&args.file, &grooms);
    summary["warnings"] = json!(losses);
    for loss in &losses {
        eprintln!(
            "groombake: warning: {}",
            super::shortened(&super::printable(loss))
        );
    }
    if grooms.len() > 1 {
        // Frames of the whole sequence; the other facts are of the first
        // topology.
        let times: Vec<f64> = grooms
            .iter()
            .flat_map(|g| g.frames.iter().map(|f| f.time))
            .collect();
        summary["frames"] = json!(times.len());
        summary["frame_times"] = json!(times);
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer_pretty(&mut out, &summary)?;
        writeln!(out)?;
        return Ok(());
    }
    writeln!(out, "file        {}", args.file.display())?;
    writeln!(out, "format      {}", groom.provenance.format)?;
    writeln!(out, "strands     {}", groom.strand_count())?;
    writeln!(out, "vertices    {}", groom.vertex_count())?;
    if let Some((min, max)) = groom.bounds() {
        writeln!(out, "bounds      {min:?} .. {max:?}")?;
    }
    writeln!(
        out,
        "units       {} (up {}), {}",
        groom.units,
        groom.up_axis,
        units_rule(&groom.provenance.units_source)
    )?;
    writeln!(out, "basis       {}", groom.basis.name())?;
    writeln!(out, "frames      {}", summary["frames"])?;
    let first = grooms.first().and_then(|g| g.frames.first());
    let last = grooms.last().and_then(|g| g.frames.last());
    if let (Some(first), Some(last)) = (first, last) {
        writeln!(out, "time        {} .. {} s", first.time, last.time)?;
    }
    if grooms.len() > 1 {
        for g in &grooms {
            writeln!(
                out,
                "topology    from {} s: {} strands, {} vertices ({} frames)",
                g.frames.first().map_or(0.0, |f| f.time),
                g.strand_count(),
                g.vertex_count(),
                g.frames.len()
            )?;
        }
    }
    for (path, strands) in prims_of(groom) {
        writeln!(out, "prim        {path} ({strands} strands)")?;
    }
    for a in &groom.attributes {
        writeln!(
            out,
            "attribute   {} ({:?} {}, {} values)",
            a.name,
            a.scope,
            a.values.type_name(),
            a.values.len()
        )?;
    }
    for problem in groom.validate() {
        writeln!(out, "note        {problem}")?;
    }
    Ok(())
}
