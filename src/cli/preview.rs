//! `groombake preview FILE -o OUT.png [--frame F | --frames a,b,c] [--color ATTR]
//! [--size WxH | --panel-size WxH] [--view front|side|top|persp] [--rest] [--head MESH]`.

use super::{values, BadInput};
use clap::Args;
use groombake::preview::{self, PreviewError, PreviewOptions, SheetEntry, View, MAX_SIZE};
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub struct PreviewArgs {
    /// The groom file, or a timeline (TOML) to draw its stages.
    #[arg(value_name = "FILE|TIMELINE", value_hint = clap::ValueHint::FilePath)]
    file: PathBuf,
    /// The picture to write (PNG).
    #[arg(short, long, value_hint = clap::ValueHint::FilePath)]
    output: PathBuf,
    /// Draw this time sample (0-based) instead of the rest pose.
    #[arg(long, conflicts_with = "frames")]
    frame: Option<usize>,
    /// A contact sheet of these time samples side by side, each labelled.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    frames: Vec<usize>,
    /// Colour strands by this scalar attribute (blue = low, red = high), with a legend.
    #[arg(long)]
    color: Option<String>,
    /// Size of the whole picture in pixels, WIDTHxHEIGHT (each 1 to 16384);
    /// a sheet's pictures and labels share it.
    #[arg(long, default_value = "1024x1024", value_parser = parse_size)]
    size: (u32, u32),
    /// Size of each picture of a sheet instead, WIDTHxHEIGHT: the sheet
    /// grows with their count (labels and gutters added).
    #[arg(long, value_parser = parse_size, conflicts_with = "size", value_name = "WxH")]
    panel_size: Option<(u32, u32)>,
    /// Where the camera looks from (Y up): front, side, top or persp. Default:
    /// a timeline's `[preview] view`, else the axis view that shows most of
    /// the change (a timeline, an animated file) or of the groom (a still one).
    #[arg(long, value_parser = values::suggest::<View>(values::VIEWS))]
    view: Option<View>,
    /// A head mesh (OBJ or glTF: metres, Y up, as `generate --scalp-mesh`)
    /// drawn opaque and skin-coloured, hiding the hair behind it. A
    /// timeline draws its own head (its always-active colliders).
    #[arg(long, value_hint = clap::ValueHint::FilePath, value_name = "MESH")]
    head: Option<PathBuf>,
    /// Draw the plastic rest shape: of a `state` export, or of a timeline's
    /// result (what the hair would look like with nothing holding it).
    #[arg(long, conflicts_with_all = ["frame", "frames"])]
    rest: bool,
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let bad = || {
        format!(
            "'{text}' is not a size: expected WIDTHxHEIGHT, each 1 to {MAX_SIZE}, e.g. 1024x768"
        )
    };
    let (width, height) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let width: u32 = width.trim().parse().map_err(|_| bad())?;
    let height: u32 = height.trim().parse().map_err(|_| bad())?;
    if !(1..=MAX_SIZE).contains(&width) || !(1..=MAX_SIZE).contains(&height) {
        return Err(bad());
    }
    Ok((width, height))
}

pub fn run(args: PreviewArgs) -> anyhow::Result<()> {
    let is_png = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(BadInput(format!(
            "{}: the preview is a PNG picture: name the output *.png",
            args.output.display()
        ))
        .into());
    }
    if importers::extension_of(&args.file) == "toml" {
        if let Some(head) = &args.head {
            return Err(BadInput(format!(
                "{}: --head {}: a timeline draws its own head (its colliders active in every stage, a wind stage's head or the generated scalp)",
                args.file.display(),
                head.display()
            ))
            .into());
        }
        return preview_timeline(&args);
    }
    let (mut groom, drawn, last) = read_drawn_frames(&args)?;
    let head = match &args.head {
        Some(path) => vec![read_head(path, &groom)?],
        None => Vec::new(),
    };
    if args.rest {
        groom = rest_shape_of_state(&args.file, groom)?;
    }
    let view = args.view.unwrap_or_else(|| match last {
        Some(last) => {
            let mut moved = groom.clone();
            moved.points = last.points;
            preview::view_showing_change(&groom, &moved)
        }
        None => preview::view_showing_spread(&groom),
    });
    // Indices into the frames read (only those drawn).
    let at = |frame: usize| drawn.iter().position(|&f| f == frame);
    let options = PreviewOptions {
        width: args.panel_size.unwrap_or(args.size).0,
        height: args.panel_size.unwrap_or(args.size).1,
        view,
        frame: args.frame.and_then(at),
        color_by: args.color.clone(),
        ..PreviewOptions::default()
    };
    let image = if args.frames.is_empty() {
        preview::render_with_surfaces(&groom, &head, &options)
    } else {
        let labels: Vec<String> = args.frames.iter().map(|f| format!("frame {f}")).collect();
        let entries: Vec<SheetEntry> = args
            .frames
            .iter()
            .zip(&labels)
            .map(|(&frame, label)| SheetEntry {
                label,
                groom: &groom,
                frame: at(frame),
                surfaces: &head,
            })
            .collect();
        sheet(&args, &entries, &options)
    }
    .map_err(|error| explain(&args.file, error))?;
    preview::write_png(&image, &args.output)?;
    Ok(())
}

/// The groom's topology and rest pose with only the frames drawn (in the
/// order of the returned frame numbers), and its last frame when the view
/// is to be chosen from it: a file is read a frame at a time, so memory
/// holds the frames drawn, not all of them. The camera frames the rest
/// pose and the frames drawn.
fn read_drawn_frames(
    args: &PreviewArgs,
) -> anyhow::Result<(groom::Groom, Vec<usize>, Option<groom::Frame>)> {
    let mut stream = importers::stream::FrameStream::open(&args.file)?;
    let mut groom = stream.groom().clone();
    super::check_groom(&args.file, &groom)?;
    let mut drawn: Vec<usize> = args
        .frame
        .into_iter()
        .chain(args.frames.iter().copied())
        .collect();
    drawn.sort_unstable();
    drawn.dedup();
    let count = stream.frame_count();
    if let Some(&frame) = drawn.iter().find(|&&f| f >= count) {
        return Err(explain(
            &args.file,
            PreviewError::NoSuchFrame { frame, count },
        ));
    }
    let mut previous_time = f64::NEG_INFINITY;
    for &index in &drawn {
        let frame = stream.frame(index)?;
        if let Some(problem) = groom
            .validate_frame(index, &frame, previous_time)
            .into_iter()
            .find(|p| p.is_fatal())
        {
            return Err(BadInput(format!("{}: {problem}", args.file.display())).into());
        }
        previous_time = frame.time;
        groom.frames.push(frame);
    }
    // `--rest` draws a still shape: its view is of the spread, not the change.
    let last = match (args.view, args.rest, count.checked_sub(1)) {
        (None, false, Some(last)) => Some(stream.frame(last)?),
        _ => None,
    };
    Ok((groom, drawn, last))
}

/// The `--head` mesh as a solid surface in the groom's units (Y up).
fn read_head(path: &Path, groom: &groom::Groom) -> anyhow::Result<preview::Surface> {
    let mesh = importers::mesh::read_mesh(path)
        .map_err(|e| BadInput(format!("--head {}: {e}", path.display())))?;
    let to_units = (1.0 / groom.units.meters_per_unit) as f32;
    let mut triangles = Vec::with_capacity(mesh.triangles.len());
    for (n, triangle) in mesh.triangles.iter().enumerate() {
        let corner = |i: u32| {
            mesh.vertices
                .get(i as usize)
                .filter(|v| v.iter().all(|c| c.is_finite()))
                .map(|v| v.map(|c| c * to_units))
        };
        match (
            corner(triangle[0]),
            corner(triangle[1]),
            corner(triangle[2]),
        ) {
            (Some(a), Some(b), Some(c)) => triangles.push([a, b, c]),
            _ => {
                return Err(BadInput(format!(
                    "--head {}: triangle {n} names a missing or non-finite vertex",
                    path.display()
                ))
                .into())
            }
        }
    }
    Ok(preview::Surface::head(triangles))
}

/// A sheet of `--size` in all, or of pictures of `--panel-size` each.
fn sheet(
    args: &PreviewArgs,
    entries: &[SheetEntry],
    options: &groombake::preview::PreviewOptions,
) -> Result<groombake::preview::Image, PreviewError> {
    if args.panel_size.is_some() {
        preview::render_sheet(entries, options)
    } else {
        preview::render_sheet_within(entries, options)
    }
}

/// The rest shape of a `state` export: the state rebuilt (metres, Y up) and
/// its rest pose integrated from the bonds' memories. The material is the
/// default one (a state file does not record the timeline's).
fn rest_shape_of_state(file: &Path, mut groom: groom::Groom) -> anyhow::Result<groom::Groom> {
    use groombake::sim::{attribute_names, Material, StrandSet};
    if groom.attribute(attribute_names::FRAME_XYZ).is_none() {
        return Err(BadInput(format!(
            "{}: --rest needs a `state` export (it has no {} attribute) or a timeline",
            file.display(),
            attribute_names::FRAME_XYZ
        ))
        .into());
    }
    groom.convert_to(groom::Units::METERS, groom::UpAxis::Y);
    let strands = StrandSet::from_state(&groom, &Material::default())
        .map_err(|e| BadInput(format!("{}: {e}", file.display())))?;
    groom.points = strands.rest_pose();
    groom.frames.clear();
    Ok(groom)
}

/// Bad requests become exit code 2, naming the file they concern.
fn explain(file: &Path, error: PreviewError) -> anyhow::Error {
    if error.is_bad_input() {
        BadInput(format!("{}: {error}", file.display())).into()
    } else {
        error.into()
    }
}

/// A timeline: bakes it in memory (no exports) and draws the groom before
/// the first stage and after each stage; `--frame N` draws only snapshot N
/// (0 = before). The timeline's `[preview]` gives defaults for colour and view.
fn preview_timeline(args: &PreviewArgs) -> anyhow::Result<()> {
    use groombake::preview::Surface;
    use groombake::timeline::bake::{bake, sheet_options, BakeOptions};
    use groombake::timeline::surfaces::snapshot_surfaces;
    use groombake::timeline::Timeline;
    if !args.frames.is_empty() {
        return Err(BadInput(format!(
            "{}: --frames applies to animated groom files; a timeline draws its stages (use --frame N for one)",
            args.file.display()
        ))
        .into());
    }
    let timeline = Timeline::load(&args.file).map_err(|e| BadInput(e.to_string()))?;
    let options = BakeOptions {
        dry: true,
        monitor: None,
        ..BakeOptions::default()
    };
    let outcome = bake(&timeline, &options).map_err(super::bake::classify)?;
    let mut preview_options = sheet_options(&timeline, &outcome.snapshots);
    (preview_options.width, preview_options.height) = args.panel_size.unwrap_or(args.size);
    if let Some(view) = args.view {
        preview_options.view = view;
    }
    if args.color.is_some() {
        preview_options.color_by = args.color.clone();
    }
    let surfaces = snapshot_surfaces(&timeline, &outcome.rods).map_err(super::bake::classify)?;
    let rest = ("rest shape".to_string(), outcome.rest.clone());
    // The rest shape is drawn alone: nothing holds it.
    let alone: &[Surface] = &[];
    let with_surfaces = |n: usize| surfaces.get(n).map_or(alone, Vec::as_slice);
    let snapshots: Vec<(&(String, groom::Groom), &[Surface])> = match args.frame {
        _ if args.rest => vec![(&rest, alone)],
        Some(n) => vec![(
            outcome.snapshots.get(n).ok_or_else(|| {
                BadInput(format!(
                    "{}: --frame {n}: the timeline has {} snapshots (before, after each stage, during a perm)",
                    args.file.display(),
                    outcome.snapshots.len()
                ))
            })?,
            with_surfaces(n),
        )],
        None => outcome
            .snapshots
            .iter()
            .enumerate()
            .map(|(n, snapshot)| (snapshot, with_surfaces(n)))
            .collect(),
    };
    let entries: Vec<SheetEntry> = snapshots
        .iter()
        .map(|((label, groom), surfaces)| SheetEntry {
            label,
            groom,
            frame: None,
            surfaces,
        })
        .collect();
    let image =
        sheet(args, &entries, &preview_options).map_err(|error| explain(&args.file, error))?;
    preview::write_png(&image, &args.output)?;
    Ok(())
}
