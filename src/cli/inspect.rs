//! `groombake inspect FILE [--json]`: a groom's facts, or a collider
//! mesh's (`.obj`, `.glb`, `.gltf` with triangles and no curves): its
//! triangles and bounds, to place it against the groom.

use super::BadInput;
use clap::Args;
use groom::Groom;
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The groom file, or a collider mesh (.obj, .glb, .gltf).
    #[arg(value_hint = clap::ValueHint::FilePath)]
    file: PathBuf,
    /// Print a JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// What `inspect` reports of a file: the groom of its (first) topology
/// and the facts of all its frames, gathered frame by frame for a file read
/// a frame at a time.
struct Facts {
    /// One groom per stretch of time with one topology; a streamed file's
    /// has no frames (they are summed up in `times`, `bounds`, `problems`).
    grooms: Vec<Groom>,
    /// Every frame's time, in file order.
    times: Vec<f64>,
    /// Of the first topology: rest points and every frame.
    bounds: Option<([f32; 3], [f32; 3])>,
    /// Of the first topology and its frames.
    problems: Vec<groom::Problem>,
}

impl Facts {
    /// A file read whole (USD, whose topology may change over time).
    fn of_sequence(grooms: Vec<Groom>) -> Facts {
        Facts {
            times: grooms
                .iter()
                .flat_map(|g| g.frames.iter().map(|f| f.time))
                .collect(),
            bounds: grooms[0].bounds(),
            problems: grooms[0].validate(),
            grooms,
        }
    }

    /// A file read a frame at a time: memory holds the topology and one
    /// frame. A fatal problem in any frame refuses the file, as reading it
    /// whole does.
    fn of_stream(path: &Path, mut stream: importers::stream::FrameStream) -> anyhow::Result<Facts> {
        let groom = stream.groom().clone();
        super::check_groom(path, &groom)?;
        let mut problems = groom.validate();
        let mut bounds = groom.bounds();
        let mut previous_time = f64::NEG_INFINITY;
        for index in 0..stream.frame_count() {
            let frame = stream.frame(index)?;
            let found = groom.validate_frame(index, &frame, previous_time);
            if let Some(problem) = found.iter().find(|p| p.is_fatal()) {
                return Err(BadInput(format!("{}: {problem}", path.display())).into());
            }
            problems.extend(found);
            previous_time = frame.time;
            let frame_bounds = groom::bounds_of(frame.points.iter());
            bounds = match (bounds, frame_bounds) {
                (Some((a, b)), Some((c, d))) => Some((
                    [0, 1, 2].map(|k| a[k].min(c[k])),
                    [0, 1, 2].map(|k| b[k].max(d[k])),
                )),
                (one, other) => one.or(other),
            };
        }
        Ok(Facts {
            times: stream.times().to_vec(),
            grooms: vec![groom],
            bounds,
            problems,
        })
    }
}

/// The facts `inspect` prints, as JSON.
fn summary(facts: &Facts) -> serde_json::Value {
    let groom = &facts.grooms[0];
    let (min, max) = facts.bounds.unwrap_or(([0.0; 3], [0.0; 3]));
    let problems = &facts.problems;
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
    let times = &facts.times;
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
        "frames": times.len(),
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
fn topology(facts: &Facts) -> Vec<serde_json::Value> {
    stretches(facts)
        .map(|(from, g, frames)| {
            json!({
                "from_time": from,
                "strands": g.strand_count(),
                "vertices": g.vertex_count(),
                "frames": frames,
            })
        })
        .collect()
}

/// Each stretch of one topology: its first time, its groom and its frame
/// count (a streamed file's one groom holds no frames: all are its).
fn stretches(facts: &Facts) -> impl Iterator<Item = (Option<f64>, &Groom, usize)> {
    let streamed = facts.grooms.len() == 1;
    facts.grooms.iter().map(move |g| {
        if streamed {
            (facts.times.first().copied(), g, facts.times.len())
        } else {
            (g.frames.first().map(|f| f.time), g, g.frames.len())
        }
    })
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
    // USD may change topology over time: a crate file of one topology
    // streams, any other USD is read whole, as a sequence. The other
    // formats are read a frame at a time.
    let read = if matches!(
        importers::extension_of(&args.file).as_str(),
        "usda" | "usdc" | "usd"
    ) {
        match importers::stream::FrameStream::open_usd_crate(&args.file) {
            Ok(Some(stream)) => Facts::of_stream(&args.file, stream),
            Ok(None) => super::read_sequence(&args.file).map(Facts::of_sequence),
            Err(error) => Err(error.into()),
        }
    } else {
        importers::stream::FrameStream::open(&args.file)
            .map_err(anyhow::Error::from)
            .and_then(|stream| Facts::of_stream(&args.file, stream))
    };
    let facts = match read {
        Ok(facts) => facts,
        Err(error) => match mesh_of(&args.file) {
            Some(mesh) => return inspect_mesh(&args, &mesh),
            None => return Err(error),
        },
    };
    let groom = &facts.grooms[0];
    let mut summary = summary(&facts);
    summary["topology"] = json!(topology(&facts));
    let losses = super::losses(&args.file, &facts.grooms);
    summary["warnings"] = json!(losses);
    for loss in &losses {
        eprintln!(
            "groombake: warning: {}",
            super::shortened(&super::printable(loss))
        );
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
    if let Some((min, max)) = facts.bounds {
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
    if let (Some(first), Some(last)) = (facts.times.first(), facts.times.last()) {
        writeln!(out, "time        {first} .. {last} s")?;
    }
    if facts.grooms.len() > 1 {
        for (from, g, frames) in stretches(&facts) {
            writeln!(
                out,
                "topology    from {} s: {} strands, {} vertices ({frames} frames)",
                from.unwrap_or(0.0),
                g.strand_count(),
                g.vertex_count(),
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
    for problem in &facts.problems {
        writeln!(out, "note        {problem}")?;
    }
    Ok(())
}
