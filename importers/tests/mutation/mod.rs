//! Mutations of real files, shared by the in-process reader harness
//! (`importers/tests/mutants.rs`) and the command-line round-trip fuzz
//! (`tests/roundtrip_fuzz.rs`): truncations, bit flips, 4- and 8-byte
//! fields set to 0, 0x7FFFFFFF and 0xFFFFFFFF, number swaps in text
//! formats, JSON-level edits for glTF. Deterministic: a seed names the same
//! mutants forever.

// Test code: a failed setup step may panic.
#![allow(clippy::unwrap_used, clippy::expect_used, dead_code)]

/// splitmix64: a few lines give a generator whose sequence never changes
/// with a crate's version, so a seed names the same mutants forever.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

/// Which mutations apply: text formats get number swaps, glTF JSON gets
/// JSON edits too.
#[derive(Clone, Copy, Debug)]
pub struct Kinds {
    pub text: bool,
    pub json: bool,
}

const FIELD_VALUES_32: [u32; 3] = [0, 0x7FFF_FFFF, 0xFFFF_FFFF];
const FIELD_VALUES_64: [u64; 3] = [0, 0x7FFF_FFFF_FFFF_FFFF, 0xFFFF_FFFF_FFFF_FFFF];
const NUMBERS: [&str; 14] = [
    "0",
    "-1",
    "1",
    "2147483647",
    "4294967295",
    "18446744073709551615",
    "99999999999999999999",
    "1e30",
    "-1e30",
    "1e-300",
    "1e400",
    "nan",
    "inf",
    "-0",
];

/// One mutant of `seed`; the name says what was done.
pub fn mutate(rng: &mut Rng, seed: &[u8], format: Kinds) -> (String, Vec<u8>) {
    let mut bytes = seed.to_vec();
    let kinds = if format.json {
        6
    } else if format.text {
        5
    } else {
        4
    };
    let at = |rng: &mut Rng, width: usize| rng.below(bytes.len().saturating_sub(width) + 1);
    match rng.below(kinds) {
        0 => {
            let cut = rng.below(bytes.len());
            bytes.truncate(cut);
            (format!("truncated at {cut}"), bytes)
        }
        1 => {
            let flips = 1 + rng.below(8);
            for _ in 0..flips {
                let i = rng.below(bytes.len());
                if let Some(b) = bytes.get_mut(i) {
                    *b ^= 1 << rng.below(8);
                }
            }
            (format!("{flips} bits flipped"), bytes)
        }
        2 => {
            let offset = at(rng, 4);
            let value = FIELD_VALUES_32[rng.below(3)];
            if let Some(field) = bytes.get_mut(offset..offset + 4) {
                field.copy_from_slice(&value.to_le_bytes());
            }
            (format!("u32 at {offset} set to {value:#x}"), bytes)
        }
        3 => {
            let offset = at(rng, 8);
            let value = FIELD_VALUES_64[rng.below(3)];
            if let Some(field) = bytes.get_mut(offset..offset + 8) {
                field.copy_from_slice(&value.to_le_bytes());
            }
            (format!("u64 at {offset} set to {value:#x}"), bytes)
        }
        4 => swap_number(rng, bytes),
        _ => edit_json(rng, bytes),
    }
}

/// Replaces one number of a text file with an extreme one.
fn swap_number(rng: &mut Rng, bytes: Vec<u8>) -> (String, Vec<u8>) {
    let mut numbers = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_digit() || b".eE+-".contains(&bytes[i])) {
                i += 1;
            }
            numbers.push(start..i);
        } else {
            i += 1;
        }
    }
    if numbers.is_empty() {
        return ("no number to swap".into(), bytes);
    }
    let range = numbers[rng.below(numbers.len())].clone();
    let number = NUMBERS[rng.below(NUMBERS.len())];
    let mut out = bytes[..range.start].to_vec();
    out.extend_from_slice(number.as_bytes());
    out.extend_from_slice(&bytes[range.end..]);
    (format!("number at {} set to {number}", range.start), out)
}

/// The JSON of a `.gltf`, or of a `.glb`'s JSON chunk, with the BIN chunk.
pub fn split_gltf(bytes: &[u8]) -> Option<(serde_json::Value, Option<Vec<u8>>)> {
    if bytes.starts_with(b"glTF") {
        let length = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
        let json = serde_json::from_slice(bytes.get(20..20 + length)?).ok()?;
        let bin = bytes.get(20 + length + 8..).map(<[u8]>::to_vec);
        Some((json, bin))
    } else {
        Some((serde_json::from_slice(bytes).ok()?, None))
    }
}

pub fn join_gltf(json: &serde_json::Value, bin: Option<Vec<u8>>) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap_or_default();
    let Some(bin) = bin else {
        return text;
    };
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((28 + text.len() + bin.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(text.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&text);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    glb
}

/// A JSON-level edit of a glTF: one value (an index, a count, an enum, an
/// object) deleted, replaced by an extreme or mistyped value, or an array
/// element duplicated many times.
fn edit_json(rng: &mut Rng, bytes: Vec<u8>) -> (String, Vec<u8>) {
    let Some((mut json, bin)) = split_gltf(&bytes) else {
        return swap_number(rng, bytes);
    };
    // Every place in the document, as a JSON pointer.
    let mut places = Vec::new();
    fn collect(value: &serde_json::Value, pointer: String, places: &mut Vec<String>) {
        match value {
            serde_json::Value::Object(map) => {
                for (key, child) in map {
                    let child_pointer =
                        format!("{pointer}/{}", key.replace('~', "~0").replace('/', "~1"));
                    places.push(child_pointer.clone());
                    collect(child, child_pointer, places);
                }
            }
            serde_json::Value::Array(items) => {
                for (k, child) in items.iter().enumerate() {
                    places.push(format!("{pointer}/{k}"));
                    collect(child, format!("{pointer}/{k}"), places);
                }
            }
            _ => {}
        }
    }
    collect(&json, String::new(), &mut places);
    if places.is_empty() {
        return swap_number(rng, bytes);
    }
    let place = places[rng.below(places.len())].clone();
    let (parent, last) = place.rsplit_once('/').unwrap_or(("", ""));
    let replacements = [
        serde_json::json!(null),
        serde_json::json!(-1),
        serde_json::json!(0),
        serde_json::json!(7),
        serde_json::json!(4_294_967_295u64),
        serde_json::json!(1e30),
        serde_json::json!("pointer"),
        serde_json::json!("\u{0}\u{1b}[31m"),
        serde_json::json!([]),
        serde_json::json!({}),
        serde_json::json!([0, 0, 0]),
    ];
    let description = match rng.below(3) {
        0 => {
            let removed = match json.pointer_mut(parent) {
                Some(serde_json::Value::Object(map)) => map.remove(last).is_some(),
                Some(serde_json::Value::Array(items)) => match last.parse::<usize>() {
                    Ok(k) if k < items.len() => {
                        items.remove(k);
                        true
                    }
                    _ => false,
                },
                _ => false,
            };
            format!("{place} removed ({removed})")
        }
        1 => {
            let value = replacements[rng.below(replacements.len())].clone();
            let text = value.to_string();
            if let Some(slot) = json.pointer_mut(&place) {
                *slot = value;
            }
            format!("{place} set to {text}")
        }
        _ => {
            let times = 1 + rng.below(1000);
            if let Some(serde_json::Value::Array(items)) = json.pointer_mut(parent) {
                if let Ok(k) = last.parse::<usize>() {
                    if let Some(item) = items.get(k).cloned() {
                        for _ in 0..times {
                            items.push(item.clone());
                        }
                    }
                }
            }
            format!("{place} repeated {times} times")
        }
    };
    (description, join_gltf(&json, bin))
}
