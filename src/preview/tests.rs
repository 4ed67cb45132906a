use super::*;
use crate::generate::{generate, GeneratorParameters, RootLayout, StrandShape};
use groom::{Attribute, Frame};

fn generated(strands: usize, layout: RootLayout, shape: StrandShape) -> Groom {
    generate(&GeneratorParameters {
        strands,
        layout,
        shape,
        ..GeneratorParameters::default()
    })
    .unwrap()
}

fn options(width: u32, height: u32) -> PreviewOptions {
    PreviewOptions {
        width,
        height,
        ..PreviewOptions::default()
    }
}

/// Pixels that differ clearly from the plain background of `image`'s row.
fn hair_pixels(image: &Image) -> Vec<(u32, u32)> {
    let plain = render(&Groom::default(), &options(image.width, image.height)).unwrap();
    let mut found = Vec::new();
    for y in 0..image.height {
        for x in 0..image.width {
            let (a, b) = (image.pixel(x, y).unwrap(), plain.pixel(x, y).unwrap());
            let difference: i32 = (0..3).map(|k| (a[k] as i32 - b[k] as i32).abs()).sum();
            if difference > 6 {
                found.push((x, y));
            }
        }
    }
    found
}

/// Two strands crossing at the origin in the front view: a horizontal one at
/// `z_horizontal`, a vertical one at `z_vertical`, coloured by a per-strand
/// attribute `heat` of 1 and 0.
fn crossing(z_horizontal: f32, z_vertical: f32, horizontal_first: bool) -> Groom {
    let horizontal: Vec<[f32; 3]> = (0..=10)
        .map(|i| [i as f32 * 0.2 - 1.0, 0.0, z_horizontal])
        .collect();
    let vertical: Vec<[f32; 3]> = (0..=10)
        .map(|i| [0.0, i as f32 * 0.2 - 1.0, z_vertical])
        .collect();
    let (strands, heat) = if horizontal_first {
        ([horizontal, vertical], vec![1.0, 0.0])
    } else {
        ([vertical, horizontal], vec![0.0, 1.0])
    };
    let mut groom = Groom::from_strands(strands);
    groom.set_attribute(Attribute::per_strand("heat", AttributeValues::Float(heat)));
    // Thick enough to cover the centre pixel whole.
    groom.set_attribute(Attribute::per_strand(
        "width",
        AttributeValues::Float(vec![0.05, 0.05]),
    ));
    groom
}

fn is_red(p: [u8; 3]) -> bool {
    p[0] as i32 > p[2] as i32 + 40 && p[0] as i32 > p[1] as i32 + 20
}

fn is_blue(p: [u8; 3]) -> bool {
    p[2] as i32 > p[0] as i32 + 40
}

#[test]
fn same_groom_same_bytes_for_any_thread_count() {
    let groom = generated(3000, RootLayout::Scalp, StrandShape::Wavy);
    let options = PreviewOptions {
        view: View::Persp,
        ..options(300, 200)
    };
    let many = render(&groom, &options).unwrap();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| render(&groom, &options).unwrap());
    assert_eq!(many, one);

    let dir = tempfile::tempdir().unwrap();
    let (first, second) = (dir.path().join("a.png"), dir.path().join("b.png"));
    write_png(&many, &first).unwrap();
    write_png(&one, &second).unwrap();
    let bytes = std::fs::read(&first).unwrap();
    assert_eq!(bytes, std::fs::read(&second).unwrap());
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    // No temporary file is left beside the output.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn png_decodes_to_the_pixels() {
    let groom = generated(200, RootLayout::Swatch, StrandShape::Wavy);
    let image = render(&groom, &options(64, 48)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.png");
    write_png(&image, &path).unwrap();
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    assert_eq!((info.width, info.height), (64, 48));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(pixels, image.pixels);
}

#[test]
fn framing_puts_the_groom_inside_the_picture() {
    let head = generated(2000, RootLayout::Scalp, StrandShape::Straight);
    let mut shifted = generated(300, RootLayout::Swatch, StrandShape::Wavy);
    // Far from the origin, in centimetres and Z up: framing must not care.
    shifted.up_axis = groom::UpAxis::Z;
    for p in &mut shifted.points {
        *p = [
            p[0] * 100.0 + 500.0,
            p[2] * 100.0 - 300.0,
            p[1] * 100.0 + 42.0,
        ];
    }
    shifted.units = groom::Units::CENTIMETERS;
    if let Some(width) = shifted.attribute_mut("width") {
        width.values.scale(100.0);
    }
    for groom in [&head, &shifted] {
        for view in [View::Front, View::Side, View::Top, View::Persp] {
            let (width, height) = (160, 120);
            let image = render(
                groom,
                &PreviewOptions {
                    view,
                    ..options(width, height)
                },
            )
            .unwrap();
            let hair = hair_pixels(&image);
            assert!(!hair.is_empty(), "{view:?}: nothing drawn");
            let min_x = hair.iter().map(|p| p.0).min().unwrap();
            let max_x = hair.iter().map(|p| p.0).max().unwrap();
            let min_y = hair.iter().map(|p| p.1).min().unwrap();
            let max_y = hair.iter().map(|p| p.1).max().unwrap();
            // Inside, with a margin.
            assert!(min_x >= 2 && min_y >= 2, "{view:?}: touches the top-left");
            assert!(
                max_x < width - 2 && max_y < height - 2,
                "{view:?}: touches the bottom-right"
            );
            // And filling the frame in one direction at least.
            let fill_x = (max_x - min_x) as f32 / width as f32;
            let fill_y = (max_y - min_y) as f32 / height as f32;
            assert!(
                fill_x.max(fill_y) > 0.75,
                "{view:?}: fills only {fill_x} x {fill_y}"
            );
        }
    }
}

#[test]
fn ramp_runs_from_blue_to_red() {
    let low = ramp(0.0);
    let high = ramp(1.0);
    assert!(low[2] > 5.0 * low[0] && low[2] > 5.0 * low[1], "{low:?}");
    assert!(
        high[0] > 5.0 * high[1] && high[0] > 5.0 * high[2],
        "{high:?}"
    );
    // Out of range and not-a-number stay on the ramp.
    assert_eq!(ramp(-3.0), low);
    assert_eq!(ramp(7.0), high);
    assert_eq!(ramp(f32::NAN), low);
}

#[test]
fn colouring_maps_the_minimum_to_blue_and_the_maximum_to_red() {
    // Two separate vertical strands: the left one has the minimum.
    let mut groom = Groom::from_strands([
        vec![[-1.0, -1.0, 0.0], [-1.0, 1.0, 0.0]],
        vec![[1.0, -1.0, 0.0], [1.0, 1.0, 0.0]],
    ]);
    groom.set_attribute(Attribute::per_strand(
        "heat",
        AttributeValues::Float(vec![0.25, 3.5]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "width",
        AttributeValues::Float(vec![0.08, 0.08]),
    ));
    let options = PreviewOptions {
        color_by: Some("heat".into()),
        ..options(400, 200)
    };
    let image = render(&groom, &options).unwrap();
    let hair = hair_pixels(&image);
    let picture_width = 400 - legend_width(400, 200);
    let strand_columns = |side: bool| {
        let mut columns: Vec<u32> = hair
            .iter()
            .filter(|p| p.1 == 100 && p.0 < picture_width && (p.0 < picture_width / 2) == side)
            .map(|p| p.0)
            .collect();
        columns.sort_unstable();
        columns[columns.len() / 2]
    };
    let left = image.pixel(strand_columns(true), 100).unwrap();
    let right = image.pixel(strand_columns(false), 100).unwrap();
    assert!(is_blue(left), "minimum drawn {left:?}");
    assert!(is_red(right), "maximum drawn {right:?}");
}

#[test]
fn legend_shows_the_ramp_and_the_range() {
    let mut groom = generated(300, RootLayout::Swatch, StrandShape::Straight);
    let values: Vec<f32> = (0..groom.vertex_count()).map(|i| i as f32 * 0.01).collect();
    groom.set_attribute(Attribute::new("heat", AttributeValues::Float(values)));
    let options = PreviewOptions {
        color_by: Some("heat".into()),
        ..options(640, 480)
    };
    let image = render(&groom, &options).unwrap();
    let legend = legend_width(640, 480);
    // Somewhere in the legend column: a red top and a blue bottom of the bar.
    let column: Vec<[u8; 3]> = (0..480)
        .filter_map(|y| {
            (640 - legend..640)
                .map(|x| image.pixel(x, y).unwrap())
                .find(|&p| is_red(p) || is_blue(p))
        })
        .collect();
    let first_red = column.iter().position(|&p| is_red(p)).unwrap();
    let last_blue = column.iter().rposition(|&p| is_blue(p)).unwrap();
    assert!(first_red < last_blue);
    assert_eq!(
        attribute_range(&groom, "heat").unwrap().map(|r| r.0),
        Some(0.0)
    );
    assert_eq!(format_number(0.0), "0");
    assert_eq!(format_number(12.345), "12.3");
    assert_eq!(format_number(-0.5), "-0.500");
    assert_eq!(format_number(0.0001234), "1.23e-4");
    assert_eq!(format_number(123456.0), "1.23e5");
}

#[test]
fn near_red_strand_covers_far_blue_one() {
    let options = PreviewOptions {
        color_by: Some("heat".into()),
        ..options(201, 201)
    };
    // Where the strands cross: the vertical one's column (the legend
    // narrows the picture), the middle row.
    let crossing_point = |image: &Image| {
        let columns: Vec<u32> = hair_pixels(image)
            .into_iter()
            .filter(|p| p.1 == 50 && p.0 < 201 - legend_width(201, 201))
            .map(|p| p.0)
            .collect();
        (columns[columns.len() / 2], 100)
    };
    for horizontal_first in [true, false] {
        // The red (heat 1) horizontal strand is nearer (front view looks along -Z).
        let groom = crossing(0.5, -0.5, horizontal_first);
        let image = render(&groom, &options).unwrap();
        let (x, y) = crossing_point(&image);
        let centre = image.pixel(x, y).unwrap();
        assert!(is_red(centre), "red over blue: {centre:?}");
        assert!(is_blue(image.pixel(x, 50).unwrap()));
        // And the other way round.
        let groom = crossing(-0.5, 0.5, horizontal_first);
        let image = render(&groom, &options).unwrap();
        let (x, y) = crossing_point(&image);
        let centre = image.pixel(x, y).unwrap();
        assert!(is_blue(centre), "blue over red: {centre:?}");
    }
}

#[test]
fn wider_hair_covers_more_pixels() {
    let strand = |width: f32| {
        let mut groom = Groom::from_strands([vec![[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]]);
        groom.set_attribute(Attribute::new(
            "width",
            AttributeValues::Float(vec![width; 2]),
        ));
        // Frame a wider area so the strand's width is not fitted to the picture.
        groom.frames.push(Frame {
            time: 0.0,
            points: vec![[-1.0, -1.0, 0.0], [1.0, 1.0, 0.0]],
            attributes: Vec::new(),
        });
        hair_pixels(&render(&groom, &options(200, 200)).unwrap()).len()
    };
    let thin = strand(1e-4);
    let thick = strand(0.1);
    assert!(
        thin > 100,
        "a sub-pixel hair is still drawn ({thin} pixels)"
    );
    assert!(thick > 4 * thin, "thick {thick}, thin {thin}");
}

#[test]
fn frames_pick_the_pose_and_share_the_camera() {
    let mut groom = Groom::from_strands([vec![[-1.0, 0.0, 0.0], [-1.0, 0.5, 0.0]]]);
    groom.frames.push(Frame {
        time: 0.0,
        points: vec![[-1.0, 0.0, 0.0], [-1.0, 0.5, 0.0]],
        attributes: Vec::new(),
    });
    groom.frames.push(Frame {
        time: 1.0,
        points: vec![[1.0, 0.0, 0.0], [1.0, 0.5, 0.0]],
        attributes: Vec::new(),
    });
    let at = |frame| {
        let image = render(
            &groom,
            &PreviewOptions {
                frame: Some(frame),
                ..options(100, 100)
            },
        )
        .unwrap();
        let hair = hair_pixels(&image);
        hair.iter().map(|p| p.0 as f32).sum::<f32>() / hair.len() as f32
    };
    let (first, second) = (at(0), at(1));
    assert!(first < 20.0 && second > 80.0, "{first} {second}");
    let error = render(
        &groom,
        &PreviewOptions {
            frame: Some(2),
            ..options(10, 10)
        },
    )
    .unwrap_err();
    assert!(matches!(
        error,
        PreviewError::NoSuchFrame { frame: 2, count: 2 }
    ));
    assert!(error.to_string().contains("0 to 1"), "{error}");
}

#[test]
fn bad_requests_are_refused_clearly() {
    let groom = generated(10, RootLayout::Swatch, StrandShape::Straight);
    for (width, height) in [(0, 10), (10, 0), (MAX_SIZE + 1, 10)] {
        let error = render(&groom, &options(width, height)).unwrap_err();
        assert!(matches!(error, PreviewError::BadSize { .. }));
        assert!(error.is_bad_input());
    }
    let error = render(
        &groom,
        &PreviewOptions {
            color_by: Some("bond_hydrogen".into()),
            ..options(10, 10)
        },
    )
    .unwrap_err();
    let message = error.to_string();
    assert!(
        message.contains("bond_hydrogen")
            && message.contains("root_uv")
            && message.contains("width"),
        "{message}"
    );
    let error = render(
        &groom,
        &PreviewOptions {
            color_by: Some("root_uv".into()),
            ..options(10, 10)
        },
    )
    .unwrap_err();
    assert!(error.to_string().contains("vec2"), "{error}");
    let mut short = groom.clone();
    short.set_attribute(Attribute::new("heat", AttributeValues::Float(vec![1.0; 3])));
    let error = render(
        &short,
        &PreviewOptions {
            color_by: Some("heat".into()),
            ..options(10, 10)
        },
    )
    .unwrap_err();
    assert!(error.to_string().contains("3 values"), "{error}");
}

#[test]
fn odd_grooms_do_not_panic() {
    let mut nan =
        Groom::from_strands([vec![[0.0, 0.0, 0.0], [f32::NAN, 1.0, 0.0], [0.0, 2.0, 0.0]]]);
    nan.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float(vec![f32::INFINITY, -1.0, 0.0]),
    ));
    let single = Groom::from_strands([vec![[1.0, 1.0, 1.0]]]);
    let mut overrun = Groom::from_strands([vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
    overrun.strand_vertex_counts = vec![2, 5];
    let flat = Groom::from_strands([vec![[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]]);
    for groom in [Groom::default(), nan, single, overrun, flat] {
        for view in [View::Front, View::Persp] {
            let image = render(
                &groom,
                &PreviewOptions {
                    view,
                    ..options(32, 16)
                },
            )
            .unwrap();
            assert_eq!(image.pixels.len(), 32 * 16 * 3);
        }
    }
}

#[test]
fn contact_sheet_lays_pictures_side_by_side_with_labels() {
    let mut groom = generated(300, RootLayout::Swatch, StrandShape::Wavy);
    let moved: Vec<[f32; 3]> = groom
        .points
        .iter()
        .map(|p| [p[0] + 0.05, p[1], p[2]])
        .collect();
    groom.frames = vec![
        Frame {
            time: 0.0,
            points: groom.points.clone(),
            attributes: Vec::new(),
        },
        Frame {
            time: 1.0,
            points: moved,
            attributes: Vec::new(),
        },
    ];
    let entries: Vec<SheetEntry> = (0..2)
        .map(|frame| SheetEntry {
            label: if frame == 0 { "frame 0" } else { "frame 1" },
            groom: &groom,
            frame: Some(frame),
            surfaces: &[],
        })
        .collect();
    let sheet = render_sheet(&entries, &options(120, 90)).unwrap();
    assert_eq!(sheet.width, 2 * 120 + 3 * GUTTER);
    assert!(sheet.height > 90 && sheet.height < 90 + 40);
    // The label strip has light text pixels.
    let label_rows = sheet.height - 90 - 2 * GUTTER;
    let text = (GUTTER..GUTTER + label_rows)
        .flat_map(|y| (0..sheet.width).map(move |x| (x, y)))
        .filter(|&(x, y)| sheet.pixel(x, y).unwrap()[0] > 200)
        .count();
    assert!(text > 20, "{text} label pixels");
    // Too many pictures for one sheet are refused, not allocated.
    let many = vec![entries[0]; 20_000];
    let error = render_sheet(&many, &options(1000, 1000)).unwrap_err();
    assert!(matches!(error, PreviewError::SheetTooLarge { .. }));
}

/// Mean colour of the hair pixels of the picture's left `picture_width` columns.
fn mean_hair_color(image: &Image, picture_width: u32) -> [f32; 3] {
    let hair: Vec<[u8; 3]> = hair_pixels(image)
        .into_iter()
        .filter(|p| p.0 < picture_width)
        .map(|(x, y)| image.pixel(x, y).unwrap())
        .collect();
    assert!(hair.len() > 50, "only {} hair pixels", hair.len());
    let mut sum = [0.0f32; 3];
    for p in &hair {
        for k in 0..3 {
            sum[k] += f32::from(p[k]);
        }
    }
    sum.map(|c| c / hair.len() as f32)
}

fn swatch_with_bonds(rate: f32) -> Groom {
    let mut groom = generated(200, RootLayout::Swatch, StrandShape::Straight);
    let rates = vec![rate; groom.vertex_count()];
    groom.set_attribute(Attribute::new(
        "bond_hydrogen",
        AttributeValues::Float(rates),
    ));
    groom
}

#[test]
fn intact_bonds_are_red_alone_and_in_a_sheet() {
    let options = PreviewOptions {
        color_by: Some("bond_hydrogen".into()),
        ..options(320, 320)
    };
    let picture_width = 320 - legend_width(320, 320);
    let intact = swatch_with_bonds(1.0);
    let alone = mean_hair_color(&render(&intact, &options).unwrap(), picture_width);
    assert!(
        alone[0] > 2.0 * alone[1] && alone[0] > 2.0 * alone[2],
        "all bonds intact (1.0) drawn {alone:?}, not red"
    );
    // The same snapshot beside a broken one in a sheet: the same colour.
    let broken = swatch_with_bonds(0.0);
    let entries = [
        SheetEntry {
            label: "",
            groom: &intact,
            frame: None,
            surfaces: &[],
        },
        SheetEntry {
            label: "",
            groom: &broken,
            frame: None,
            surfaces: &[],
        },
    ];
    let scene = Scene::new(&entries, &options).unwrap();
    let in_sheet = mean_hair_color(&scene.draw(&entries[0]).unwrap(), picture_width);
    for k in 0..3 {
        assert!(
            (alone[k] - in_sheet[k]).abs() < 2.0,
            "alone {alone:?}, in a sheet {in_sheet:?}"
        );
    }
    let broken_color = mean_hair_color(&scene.draw(&entries[1]).unwrap(), picture_width);
    assert!(
        broken_color[2] > 2.0 * broken_color[0],
        "all bonds broken (0.0) drawn {broken_color:?}, not blue"
    );
}

#[test]
fn a_constant_attribute_is_drawn_at_the_end_of_the_ramp_it_reaches() {
    let mut groom = generated(200, RootLayout::Swatch, StrandShape::Straight);
    let values = vec![2.5; groom.vertex_count()];
    groom.set_attribute(Attribute::new("heat", AttributeValues::Float(values)));
    let options = PreviewOptions {
        color_by: Some("heat".into()),
        ..options(320, 320)
    };
    let picture_width = 320 - legend_width(320, 320);
    let color = mean_hair_color(&render(&groom, &options).unwrap(), picture_width);
    assert!(
        color[0] > 2.0 * color[1] && color[0] > 2.0 * color[2],
        "a constant 2.5 drawn {color:?}: expected the red end (legend 0 to 2.5)"
    );
    assert_eq!(widen_constant((2.5, 2.5)), (0.0, 2.5));
    assert_eq!(widen_constant((-1.0, -1.0)), (-1.0, 0.0));
    assert_eq!(widen_constant((0.0, 0.0)), (0.0, 1.0));
    assert_eq!(widen_constant((0.2, 0.7)), (0.2, 0.7));
}

/// A ball of `radius` at the origin as a head surface.
fn ball_head(radius: f32) -> Surface {
    let (vertices, indices) = crate::sim::parry3d::shape::Ball::new(radius).to_trimesh(48, 24);
    let triangles = indices
        .iter()
        .map(|t| t.map(|i| vertices[i as usize]).map(|v| [v.x, v.y, v.z]))
        .collect();
    Surface::head(triangles)
}

fn is_skin(p: [u8; 3]) -> bool {
    p[0] > 120 && p[0] as i32 > p[1] as i32 + 20 && p[1] as i32 > p[2] as i32 + 5
}

/// Brown hair, darker than skin.
fn is_hair(p: [u8; 3]) -> bool {
    p[0] < 110 && p[0] as i32 > p[2] as i32 + 10
}

#[test]
fn the_head_is_skin_coloured_and_hides_the_hair_behind_it() {
    let radius = 0.1;
    // A strand behind the head, one across in front of it, and one lying on
    // the face (half a millimetre above the surface).
    let behind: Vec<[f32; 3]> = (0..=12)
        .map(|i| [0.0, i as f32 * 0.05 - 0.3, -0.15])
        .collect();
    let across: Vec<[f32; 3]> = (0..=12)
        .map(|i| [i as f32 * 0.05 - 0.3, -0.05, 0.15])
        .collect();
    let lying: Vec<[f32; 3]> = (0..=12)
        .map(|i| {
            let y = i as f32 * 0.01 - 0.06;
            let r = radius + 5e-4;
            [0.05, y, (r * r - 0.05 * 0.05 - y * y).sqrt()]
        })
        .collect();
    let mut groom = Groom::from_strands([behind, across, lying]);
    groom.set_attribute(Attribute::per_strand(
        "width",
        AttributeValues::Float(vec![0.02, 0.02, 0.01]),
    ));
    let head = [ball_head(radius)];
    let image = render_with_surfaces(&groom, &head, &options(200, 200)).unwrap();
    // The groom spans 0.6 each way, framed with a 6 % margin, centred.
    let scale = 200.0 * 0.88 / 0.6;
    let at = |x: f32, y: f32| {
        image
            .pixel((100.0 + x * scale) as u32, (100.0 - y * scale) as u32)
            .unwrap()
    };
    let face = at(-0.05, 0.03);
    assert!(is_skin(face), "the face is skin-coloured: {face:?}");
    let over_behind = at(0.0, 0.03);
    assert!(
        is_skin(over_behind),
        "the strand behind the head is hidden: {over_behind:?}"
    );
    let above = at(0.0, 0.25);
    assert!(is_hair(above), "the strand shows above the head: {above:?}");
    let front = at(-0.05, -0.05);
    assert!(
        is_hair(front),
        "the strand in front covers the face: {front:?}"
    );
    let on_face = at(0.05, 0.0);
    assert!(
        is_hair(on_face),
        "hair lying on the face shows: {on_face:?}"
    );
    // Lit, not flat: the lit side of the face is lighter than its edge.
    let edge = at(-0.093, 0.0);
    assert!(
        is_skin(edge) && edge[0] < face[0],
        "the face {face:?} and its edge {edge:?}"
    );
    // The same picture for any thread count.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| render_with_surfaces(&groom, &head, &options(200, 200)).unwrap());
    assert_eq!(one, image);
}

#[test]
fn head_samples_draw_their_head_solid_from_three_quarters() {
    use crate::timeline::{bake::sheet_options, surfaces::snapshot_surfaces, Timeline};
    let samples = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("samples");
    // (sample, solid surfaces before the first stage, others then)
    for (name, solid, other) in [
        // The wind model's own head ellipsoid.
        ("wind.toml", 1, 0),
        // A mesh head (an always-active collider); the pillow comes later.
        ("bed_head.toml", 1, 0),
        // A ball head.
        ("full_head.toml", 1, 0),
        // A swatch: no head; its plate is drawn as before.
        ("blow_dry.toml", 0, 0),
    ] {
        let timeline = Timeline::load(&samples.join(name)).unwrap();
        let surfaces = snapshot_surfaces(&timeline, &[]).unwrap();
        let before = &surfaces[0];
        assert_eq!(
            before.iter().filter(|s| s.solid).count(),
            solid,
            "{name}: heads"
        );
        assert_eq!(
            before.iter().filter(|s| !s.solid).count(),
            other,
            "{name}: other surfaces"
        );
        assert!(before
            .iter()
            .filter(|s| s.solid)
            .all(|s| s.color == head::SKIN && s.triangles.len() > 500));
        let view = sheet_options(&timeline, &[]).view;
        assert_eq!(view == View::Persp, solid > 0, "{name}: view {view:?}");
    }
}
