use super::document::percent_decode;
use super::lines::chain_segments;
use super::scene::{multiply, transform, Matrix};
use super::*;
use base64::Engine;
use groom::{AttributeValues, Units};

/// A hand-made glTF: a LINE_STRIP under a translated parent and a scaled
/// child, with a morph target driven by a LINEAR weights sampler, and a
/// LINES primitive with u16 indices at the root. Returns (JSON, buffer).
fn hand_made(uri: Option<&str>) -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    let mut floats = |values: &[f32]| {
        for v in values {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    };
    floats(&[0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0]); // 0: strip positions
    floats(&[0.1, 0.2, 0.3]); // 36: strip widths
    floats(&[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0]); // 48: target deltas
    floats(&[0.0, 1.0]); // 84: times
    floats(&[0.0, 0.5]); // 92: weights
    floats(&[5.0, 0.0, 0.0, 5.0, 1.0, 0.0, 6.0, 0.0, 0.0, 6.0, 1.0, 0.0]); // 100: lines positions
    for i in [0u16, 1, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes()); // 148: indices
    }
    let mut floats = |values: &[f32]| {
        for v in values {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    };
    floats(&[0.4, 0.5, 0.6, 0.7]); // 156: lines widths
    let uri = uri.map(|u| format!(r#","uri":"{u}""#)).unwrap_or_default();
    let view = |offset: usize, length: usize| {
        format!(r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{length}}}"#)
    };
    let views = [
        view(0, 36),
        view(36, 12),
        view(48, 36),
        view(84, 8),
        view(92, 8),
        view(100, 48),
        view(148, 8),
        view(156, 16),
    ]
    .join(",");
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,2]}}],
        "nodes":[{{"translation":[10,0,0],"children":[1]}},{{"scale":[2,2,2],"mesh":0}},{{"mesh":1}}],
        "meshes":[
          {{"primitives":[{{"mode":3,"attributes":{{"POSITION":0,"_WIDTH":1}},"targets":[{{"POSITION":2}}]}}],"weights":[0.25]}},
          {{"primitives":[{{"mode":1,"attributes":{{"POSITION":5,"_WIDTH":7}},"indices":6}}]}}],
        "animations":[{{"channels":[{{"sampler":0,"target":{{"node":1,"path":"weights"}}}}],
          "samplers":[{{"input":3,"output":4,"interpolation":"LINEAR"}}]}}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[0,2,0]}},
          {{"bufferView":1,"componentType":5126,"count":3,"type":"SCALAR"}},
          {{"bufferView":2,"componentType":5126,"count":3,"type":"VEC3"}},
          {{"bufferView":3,"componentType":5126,"count":2,"type":"SCALAR"}},
          {{"bufferView":4,"componentType":5126,"count":2,"type":"SCALAR"}},
          {{"bufferView":5,"componentType":5126,"count":4,"type":"VEC3","min":[5,0,0],"max":[6,1,0]}},
          {{"bufferView":6,"componentType":5123,"count":4,"type":"SCALAR"}},
          {{"bufferView":7,"componentType":5126,"count":4,"type":"SCALAR"}}],
        "bufferViews":[{views}],
        "buffers":[{{"byteLength":{}{uri}}}]}}"#,
        bin.len()
    );
    (json, bin)
}

fn check_hand_made(groom: &Groom) {
    assert_eq!(groom.strand_vertex_counts, vec![3, 2, 2]);
    assert_eq!(
        groom.points,
        vec![
            [10.0, 0.0, 0.0],
            [10.0, 2.0, 0.0],
            [10.0, 4.0, 0.0],
            [5.0, 0.0, 0.0],
            [5.0, 1.0, 0.0],
            [6.0, 0.0, 0.0],
            [6.0, 1.0, 0.0],
        ]
    );
    assert_eq!(
        groom.attribute("width").unwrap().values,
        AttributeValues::Float(vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7])
    );
    assert_eq!(groom.frames.len(), 2);
    assert_eq!(groom.frames[0].points, groom.points);
    assert_eq!(groom.frames[1].time, 1.0);
    // Weight 0.5 of a +1 x delta, scaled by 2 by the node.
    assert_eq!(groom.frames[1].points[2], [11.0, 4.0, 0.0]);
    assert_eq!(groom.frames[1].points[3], [5.0, 0.0, 0.0]);
    assert_eq!(groom.units, Units::METERS);
}

#[test]
fn reads_embedded_gltf_with_scene_graph_and_morph_animation() {
    let (_, bin) = hand_made(None);
    let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
    let (json, _) = hand_made(Some(&format!(
        "data:application/octet-stream;base64,{payload}"
    )));
    let groom = parse(Path::new("t.gltf"), json.as_bytes()).unwrap();
    check_hand_made(&groom);
}

#[test]
fn reads_glb_and_external_buffers() {
    let (json, bin) = hand_made(None);
    let mut json = json.into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    check_hand_made(&parse(Path::new("t.glb"), &glb).unwrap());
    for cut in 0..glb.len() {
        assert!(parse(Path::new("t.glb"), &glb[..cut]).is_err(), "cut {cut}");
    }

    let dir = std::env::temp_dir().join(format!("importers-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("hair buffer.bin"), &bin).unwrap();
    let (json, _) = hand_made(Some("hair%20buffer.bin"));
    std::fs::write(dir.join("t.gltf"), &json).unwrap();
    check_hand_made(&read(&dir.join("t.gltf")).unwrap());
    std::fs::write(dir.join("hair buffer.bin"), &bin[..100]).unwrap();
    let error = read(&dir.join("t.gltf")).unwrap_err().to_string();
    assert!(error.contains(":/buffers/0: byteLength is 172"), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn accessor_past_its_view_names_the_accessor() {
    let (_, bin) = hand_made(None);
    let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
    let (json, _) = hand_made(Some(&format!(
        "data:application/octet-stream;base64,{payload}"
    )));
    let json = json.replacen(
        r#""count":4,"type":"VEC3""#,
        r#""count":400,"type":"VEC3""#,
        1,
    );
    let error = parse(Path::new("t.gltf"), json.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        error.starts_with("t.gltf:/accessors/5: 400 elements"),
        "{error}"
    );
    let json = hand_made(Some("data:x;base64,@@")).0;
    let error = parse(Path::new("t.gltf"), json.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(error.contains("/buffers/0: bad base64"), "{error}");
}

#[test]
fn extras_markers_name_scope_and_type_attributes() {
    let (_, bin) = hand_made(None);
    let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
    let (json, _) = hand_made(Some(&format!(
        "data:application/octet-stream;base64,{payload}"
    )));
    let marked = |json: &str, extras: &str| {
        // The two _WIDTH accessors (1 and 7): the only SCALAR FLOAT
        // accessors of three elements and of four.
        json.replacen(
            r#""count":3,"type":"SCALAR"}"#,
            &format!(r#""count":3,"type":"SCALAR","extras":{extras}}}"#),
            1,
        )
        .replacen(
            r#""componentType":5126,"count":4,"type":"SCALAR"}"#,
            &format!(r#""componentType":5126,"count":4,"type":"SCALAR","extras":{extras}}}"#),
            1,
        )
    };
    // The strip's widths differ along its strand: the per-strand marker
    // is not honoured, the name is.
    let json_marked = marked(&json, r#"{"groombake":{"name":"Width","scope":"strand"}}"#);
    assert_ne!(json_marked, json);
    let groom = parse(Path::new("t.gltf"), json_marked.as_bytes()).unwrap();
    let width = groom.attribute("Width").unwrap();
    assert_eq!(width.scope, groom::Scope::Vertex);
    assert_eq!(width.values.len(), 7);
    // Fractional floats marked int stay floats; a split encoding on a
    // FLOAT accessor is ignored; unknown extras are harmless.
    for extras in [
        r#"{"groombake":{"type":"int","encoding":"i32_as_u16x2"}}"#,
        r#"{"groombake":7}"#,
        r#"[1,2]"#,
    ] {
        let json_marked = marked(&json, extras);
        let groom = parse(Path::new("t.gltf"), json_marked.as_bytes()).unwrap();
        assert_eq!(
            groom.attribute("width").unwrap().values,
            AttributeValues::Float(vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]),
            "{extras}"
        );
    }
}

#[test]
fn segments_chain_into_strands() {
    assert_eq!(
        chain_segments(&[0, 1, 1, 2, 3, 4, 4, 5, 5, 6, 7, 7, 7, 8]),
        vec![vec![0, 1, 2], vec![3, 4, 5, 6], vec![7], vec![7, 8]]
    );
}

#[test]
fn matrices_compose_parent_first() {
    let translate: Matrix = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [10.0, 0.0, 0.0, 1.0],
    ];
    let scale: Matrix = [
        [2.0, 0.0, 0.0, 0.0],
        [0.0, 2.0, 0.0, 0.0],
        [0.0, 0.0, 2.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    // Parent translates, child scales: the point is scaled, then moved.
    let world = multiply(&translate, &scale);
    assert_eq!(transform(&world, [1.0, 1.0, 1.0]), [12.0, 2.0, 2.0]);
}

#[test]
fn percent_escapes() {
    assert_eq!(percent_decode("my%20hair.bin"), "my hair.bin");
    assert_eq!(percent_decode("odd%2"), "odd%2");
}

/// Four vertices of a unit square drawn as TRIANGLES (u8 indices) by a
/// translated node and a mirroring node, as a TRIANGLE_STRIP, a
/// TRIANGLE_FAN, and a LINE_STRIP that triangle reading skips.
fn triangle_scene() -> String {
    let mut bin = Vec::new();
    for v in [
        0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0,
    ] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    bin.extend_from_slice(&[0, 1, 2, 2, 1, 3, 0, 0]);
    let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
    let primitive = |mode: u32, indices: &str| {
        format!(r#"{{"primitives":[{{"mode":{mode},"attributes":{{"POSITION":0}}{indices}}}]}}"#)
    };
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1,2,3,4]}}],
        "nodes":[{{"translation":[10,0,0],"mesh":0}},{{"scale":[-1,1,1],"mesh":0}},{{"mesh":1}},{{"mesh":2}},{{"mesh":3}}],
        "meshes":[{},{},{},{}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
          {{"bufferView":1,"componentType":5121,"count":6,"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":6}}],
        "buffers":[{{"byteLength":56,"uri":"data:application/octet-stream;base64,{payload}"}}]}}"#,
        primitive(4, r#","indices":1"#),
        primitive(5, ""),
        primitive(6, ""),
        primitive(3, ""),
    )
}

fn normal_z(vertices: &[[f32; 3]], [a, b, c]: [u32; 3]) -> f32 {
    let (a, b, c) = (
        vertices[a as usize],
        vertices[b as usize],
        vertices[c as usize],
    );
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

#[test]
fn triangles_of_every_mode_with_transforms_and_mirroring() {
    let json = triangle_scene();
    let (vertices, triangles) = parse_triangles(Path::new("t.gltf"), json.as_bytes()).unwrap();
    assert_eq!(vertices.len(), 16);
    assert_eq!(vertices[1], [11.0, 0.0, 0.0]);
    assert_eq!(vertices[5], [-1.0, 0.0, 0.0]);
    assert_eq!(
        triangles,
        vec![
            [0, 1, 2],
            [2, 1, 3],
            // Mirrored by scale -1: winding reversed.
            [4, 6, 5],
            [6, 7, 5],
            // Strip: odd triangles swap their last two corners.
            [8, 9, 10],
            [9, 11, 10],
            // Fan around the first vertex.
            [13, 14, 12],
            [14, 15, 12],
        ]
    );
    // The mirrored copies still face +z, like the originals.
    for &t in &triangles[..6] {
        assert!(normal_z(&vertices, t) > 0.0, "{t:?}");
    }
    // Strokes are no triangles; the curve reader still finds the line.
    let groom = parse(Path::new("t.gltf"), json.as_bytes()).unwrap();
    assert_eq!(groom.strand_vertex_counts, vec![4]);
}

#[test]
fn malformed_triangles_name_the_place() {
    let json = triangle_scene();
    let cases = [
        (
            r#""componentType":5121,"count":6"#,
            r#""componentType":5121,"count":5"#,
            "t.gltf:/meshes/0/primitives/0: TRIANGLES primitive with 5 vertices",
        ),
        (
            r#""count":4,"type":"VEC3""#,
            r#""count":40,"type":"VEC3""#,
            "t.gltf:/accessors/0: 40 elements",
        ),
        (
            r#""componentType":5121,"count":6,"type":"SCALAR""#,
            r#""componentType":5126,"count":1,"type":"SCALAR""#,
            "t.gltf:/accessors/1: indices are not unsigned integers",
        ),
    ];
    for (from, to, expected) in cases {
        let bad = json.replacen(from, to, 1);
        assert_ne!(bad, json);
        let e = parse_triangles(Path::new("t.gltf"), bad.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(expected), "{e}");
    }
    // Index 3 becomes 9, past the four vertices.
    let mut bin = Vec::new();
    for v in [
        0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0,
    ] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let good = base64::engine::general_purpose::STANDARD
        .encode([&bin[..], &[0, 1, 2, 2, 1, 3, 0, 0]].concat());
    let bad = base64::engine::general_purpose::STANDARD
        .encode([&bin[..], &[0, 1, 2, 2, 1, 9, 0, 0]].concat());
    let json = json.replacen(&good, &bad, 1);
    let e = parse_triangles(Path::new("t.gltf"), json.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("t.gltf:/accessors/1: index 9 is out of range (4 vertices)"),
        "{e}"
    );
}

#[test]
fn every_cut_of_the_pillow_sample_is_an_error() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/pillow.glb");
    let glb = std::fs::read(&path).unwrap();
    let (vertices, triangles) = parse_triangles(&path, &glb).unwrap();
    assert_eq!((vertices.len(), triangles.len()), (8, 12));
    for cut in 0..glb.len() {
        assert!(parse_triangles(&path, &glb[..cut]).is_err(), "cut {cut}");
    }
}

#[test]
fn garbage_is_an_error() {
    for bytes in [&b""[..], b"{", b"glTF\x02\x00\x00\x00", b"{\"asset\":{}}"] {
        assert!(parse(Path::new("t.glb"), bytes).is_err());
    }
}

/// The hand-made file with its buffer embedded, as JSON text.
fn embedded() -> String {
    let (_, bin) = hand_made(None);
    let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
    hand_made(Some(&format!(
        "data:application/octet-stream;base64,{payload}"
    )))
    .0
}

fn error_of(json: &str) -> String {
    parse(Path::new("t.gltf"), json.as_bytes())
        .unwrap_err()
        .to_string()
}

#[test]
fn unknown_animation_target_path_is_read_as_a_loss() {
    // glTF's schema allows other paths (KHR_animation_pointer uses
    // "pointer"); the gltf crate's wrapper unwrapped them and panicked.
    // The channel animates nothing groombake reads: named as a loss.
    let json = embedded().replacen(r#""path":"weights""#, r#""path":"pointer""#, 1);
    let groom = parse(Path::new("t.gltf"), json.as_bytes()).unwrap();
    assert_eq!(groom.strand_vertex_counts, vec![3, 2, 2]);
    assert!(groom.frames.is_empty());
    assert_eq!(
        groom.provenance.losses,
        vec![
            "1 animation channel(s) not read (frames are the strands' morph-target weights, \
             from the first animation with them): \
             /animations/0/channels/0 (a path glTF does not define of node 1)"
                .to_string()
        ]
    );
    // The weights channel it replaced is read with no loss.
    let groom = parse(Path::new("t.gltf"), embedded().as_bytes()).unwrap();
    assert!(!groom.frames.is_empty());
    assert!(
        groom.provenance.losses.is_empty(),
        "{:?}",
        groom.provenance.losses
    );
}

#[test]
fn animation_channel_naming_a_missing_node_is_an_error() {
    let json = embedded().replacen(r#""node":1,"path""#, r#""node":9,"path""#, 1);
    let error = error_of(&json);
    assert_eq!(
        error,
        "t.gltf:/animations/0/channels/0/target/node: node 9 does not exist (the file has 3 nodes)"
    );
}

#[test]
fn primitive_attribute_naming_a_missing_accessor_is_an_error() {
    // POSITION past the accessors panicked inside the gltf crate's own
    // validation; a custom attribute's in its wrapper.
    for (from, to, place) in [
        (
            r#""POSITION":0,"_WIDTH":1"#,
            r#""POSITION":80,"_WIDTH":1"#,
            "/meshes/0/primitives/0/attributes/POSITION: accessor 80",
        ),
        (
            r#""POSITION":0,"_WIDTH":1"#,
            r#""POSITION":0,"_WIDTH":81"#,
            "/meshes/0/primitives/0/attributes/_WIDTH: accessor 81",
        ),
        (
            r#""targets":[{"POSITION":2}]"#,
            r#""targets":[{"POSITION":82}]"#,
            "/meshes/0/primitives/0/targets/0/POSITION: accessor 82",
        ),
        (
            r#""indices":6"#,
            r#""indices":83"#,
            "/meshes/1/primitives/0/indices: accessor 83",
        ),
    ] {
        let json = embedded().replacen(from, to, 1);
        let error = error_of(&json);
        assert!(
            error.starts_with(&format!(
                "t.gltf:{place} does not exist (the file has 8 accessors)"
            )),
            "{error}"
        );
    }
    // A mesh collider reads the same way.
    let json = triangle_scene().replacen(r#""POSITION":0"#, r#""POSITION":5"#, 1);
    let error = parse_triangles(Path::new("t.gltf"), json.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        error.starts_with(
            "t.gltf:/meshes/0/primitives/0/attributes/POSITION: accessor 5 does not exist"
        ),
        "{error}"
    );
}

#[test]
fn every_reference_past_its_array_is_an_error() {
    for (from, to, place) in [
        (r#""scene":0"#, r#""scene":4"#, "/scene: scene 4"),
        (
            r#""nodes":[0,2]"#,
            r#""nodes":[0,7]"#,
            "/scenes/0/nodes/1: node 7",
        ),
        (
            r#""children":[1]"#,
            r#""children":[5]"#,
            "/nodes/0/children/0: node 5",
        ),
        (r#""mesh":1}"#, r#""mesh":6}"#, "/nodes/2/mesh: mesh 6"),
        (
            r#""sampler":0"#,
            r#""sampler":3"#,
            "/animations/0/channels/0/sampler: sampler 3",
        ),
        (
            r#""input":3"#,
            r#""input":30"#,
            "/animations/0/samplers/0/input: accessor 30",
        ),
        (
            r#"{"bufferView":7,"#,
            r#"{"bufferView":70,"#,
            "/accessors/7/bufferView: bufferView 70",
        ),
        (
            r#"{"buffer":0,"byteOffset":156"#,
            r#"{"buffer":2,"byteOffset":156"#,
            "/bufferViews/7/buffer: buffer 2",
        ),
    ] {
        let json = embedded().replacen(from, to, 1);
        assert_ne!(json, embedded(), "{from}");
        let error = error_of(&json);
        assert!(
            error.starts_with(&format!("t.gltf:{place} does not exist")),
            "{error}"
        );
    }
}

#[test]
fn unknown_enums_are_errors_naming_the_field() {
    for (from, to, expected) in [
        (
            r#""mode":1"#,
            r#""mode":9"#,
            "/meshes/1/primitives/0/mode: unknown primitive mode",
        ),
        (
            r#""interpolation":"LINEAR""#,
            r#""interpolation":"SMOOTH""#,
            "/animations/0/samplers/0/interpolation: unknown interpolation",
        ),
        (
            r#""componentType":5123"#,
            r#""componentType":5124"#,
            "/accessors/6/componentType: unknown componentType",
        ),
        (
            r#""type":"SCALAR"}"#,
            r#""type":"MAT9"}"#,
            "/accessors/1/type: unknown accessor type",
        ),
    ] {
        let json = embedded().replacen(from, to, 1);
        assert_ne!(json, embedded(), "{from}");
        assert_eq!(error_of(&json), format!("t.gltf:{expected}"));
    }
}

#[test]
fn glb_length_field_below_its_header_is_an_error() {
    // The gltf crate's GLB reader subtracted the 12-byte header from this
    // field unchecked (a panic in debug builds).
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&3u32.to_le_bytes());
    let error = parse(Path::new("t.glb"), &glb).unwrap_err().to_string();
    assert_eq!(
        error,
        "t.glb:offset 8: GLB length is 3 but the file has 12 bytes"
    );
}

#[test]
fn control_characters_from_the_file_are_escaped_in_errors() {
    let json = embedded().replacen(
        r#""uri":"data:"#,
        r#""uri":"http://\u0000\u001b[31m/x","was":"data:"#,
        1,
    );
    let error = error_of(&json);
    assert!(
        error.contains(r"cannot read remote buffer http://\u{0}\u{1b}[31m/x"),
        "{error}"
    );
    assert!(!error.chars().any(char::is_control), "{error:?}");
}

#[test]
fn morph_targets_without_positions_take_no_memory_per_vertex() {
    // A million targets that move nothing: a few bytes of JSON each.
    let many = vec!["{}"; 1_000_000].join(",");
    let json = embedded().replacen(
        r#""targets":[{"POSITION":2}]"#,
        &format!(r#""targets":[{{"POSITION":2}},{many}]"#),
        1,
    );
    let groom = parse(Path::new("t.gltf"), json.as_bytes());
    // One weight per keyframe no longer matches the target count.
    assert!(groom.is_err());
}

#[test]
fn one_accessor_referenced_very_often_is_refused_not_decoded_each_time() {
    let (_, bin) = hand_made(None);
    let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
    // A 4 MB accessor (in a buffer put first) used by 4,000 line
    // primitives: 16 GB decoded if each decoded it anew.
    let big = vec![0u8; 4 << 20];
    let big_payload = base64::engine::general_purpose::STANDARD.encode(&big);
    let primitive = r#"{"mode":1,"attributes":{"POSITION":8}}"#;
    let json = hand_made(Some(&format!(
        "data:application/octet-stream;base64,{payload}"
    )))
    .0
    .replacen(
        r#"{"primitives":[{"mode":1,"#,
        &format!(r#"{{"primitives":[{},{{"mode":1,"#, vec![primitive; 4000].join(",")),
        1,
    )
    .replacen(
        r#"{"bufferView":7,"componentType":5126,"count":4,"type":"SCALAR"}]"#,
        r#"{"bufferView":7,"componentType":5126,"count":4,"type":"SCALAR"},{"bufferView":8,"componentType":5126,"count":349525,"type":"VEC3"}]"#,
        1,
    )
    .replacen(
        r#"{"buffer":0,"byteOffset":156,"byteLength":16}"#,
        r#"{"buffer":0,"byteOffset":156,"byteLength":16},{"buffer":0,"byteLength":4194300}"#,
        1,
    )
    .replacen(
        r#""buffers":[{"#,
        &format!(
            r#""buffers":[{{"byteLength":4194304,"uri":"data:application/octet-stream;base64,{big_payload}"}},{{"#
        ),
        1,
    );
    let error = error_of(&json);
    assert!(error.contains("more than 8 times its bytes"), "{error}");
}

#[test]
fn keyframes_times_points_beyond_the_files_bytes_are_refused_before_allocating() {
    // 3,000,000 keyframes (12 MB of times) of 7 points would be 252 MB of
    // frames: more than the file's bytes back.
    let keys = 3_000_000usize;
    let (_, mut bin) = hand_made(None);
    let times_at = bin.len();
    for k in 0..keys {
        bin.extend_from_slice(&(k as f32).to_le_bytes());
    }
    let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
    let json = hand_made(Some(&format!(
        "data:application/octet-stream;base64,{payload}"
    )))
    .0
    .replacen(r#""byteLength":172"#, &format!(r#""byteLength":{}"#, bin.len()), 1)
    .replacen(
        r#"{"buffer":0,"byteOffset":84,"byteLength":8}"#,
        &format!(r#"{{"buffer":0,"byteOffset":{times_at},"byteLength":{}}}"#, 4 * keys),
        1,
    )
    .replacen(
        r#""componentType":5126,"count":2,"type":"SCALAR"}"#,
        &format!(r#""componentType":5126,"count":{keys},"type":"SCALAR"}}"#),
        1,
    )
    .replacen(
        r#"{"bufferView":4,"componentType":5126,"count":2,"#,
        &format!(r#"{{"bufferView":8,"componentType":5126,"count":{keys},"#),
        1,
    )
    .replacen(
        r#"{"buffer":0,"byteOffset":156,"byteLength":16}"#,
        &format!(
            r#"{{"buffer":0,"byteOffset":156,"byteLength":16}},{{"buffer":0,"byteOffset":{times_at},"byteLength":{}}}"#,
            4 * keys
        ),
        1,
    );
    let error = error_of(&json);
    assert!(
        error.starts_with(
            "t.gltf:/animations/0: the file's references ask to decode more than 8 times"
        ),
        "{error}"
    );
}

/// A triangle with TEXCOORD_0, drawn by a plain and a mirroring node: the
/// corner UVs come back with V flipped (glTF's V runs down) and follow the
/// mirrored winding.
#[test]
fn triangle_texcoords_become_corner_uvs() {
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.25f32, 0.75, 0.5, 0.75, 0.25, 0.25] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
        "nodes":[{{"mesh":0}},{{"scale":[-1,1,1],"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}}}}]}}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
          {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],
        "buffers":[{{"byteLength":60,"uri":"data:application/octet-stream;base64,{payload}"}}]}}"#
    );
    let mesh = parse_mesh(Path::new("t.gltf"), json.as_bytes()).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [3, 5, 4]]);
    assert_eq!(
        mesh.corner_uvs,
        Some(vec![
            [[0.25, 0.25], [0.5, 0.25], [0.25, 0.75]],
            [[0.25, 0.25], [0.25, 0.75], [0.5, 0.25]],
        ])
    );
    let without = json.replace(r#","TEXCOORD_0":1"#, "");
    let mesh = parse_mesh(Path::new("t.gltf"), without.as_bytes()).unwrap();
    assert_eq!((mesh.triangles.len(), mesh.corner_uvs), (2, None));
}
