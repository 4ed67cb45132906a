//! Decoding a crate file's values: the value reps (inlined, arrays,
//! compressed integer and float arrays), composition list ops and time
//! samples, each bounded by the bytes that are there and the decode budget.

use super::*;

/// How the numbers of an element are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Scalar {
    U8,
    I32,
    U32,
    I64,
    U64,
    F16,
    F32,
    F64,
}

impl Scalar {
    pub(super) fn size(self) -> u64 {
        match self {
            Scalar::U8 => 1,
            Scalar::F16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    pub(super) fn decode(self, bytes: &[u8]) -> f64 {
        let mut raw = [0u8; 8];
        let n = bytes.len().min(8);
        raw[..n].copy_from_slice(&bytes[..n]);
        let word = u64::from_le_bytes(raw);
        match self {
            Scalar::U8 => f64::from(raw[0]),
            Scalar::I32 => f64::from(word as u32 as i32),
            Scalar::U32 => f64::from(word as u32),
            Scalar::I64 => word as i64 as f64,
            Scalar::U64 => word as f64,
            Scalar::F16 => f64::from(half_to_f32(word as u16)),
            Scalar::F32 => f64::from(f32::from_bits(word as u32)),
            Scalar::F64 => f64::from_bits(word),
        }
    }
}

/// What a crate type id holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Numbers {
        scalar: Scalar,
        components: usize,
        matrix: bool,
        quaternion: bool,
    },
    Token,
    String,
    AssetPath,
    TokenVector,
    StringVector,
    /// `SdfPathListOp` (inherits, specializes).
    PathListOp,
    /// `SdfReferenceListOp`.
    ReferenceListOp,
    /// `SdfPayloadListOp`, and a single `SdfPayload` (older files).
    PayloadListOp,
    Payload,
    DoubleVector,
    Specifier,
    Variability,
    TimeSamples,
    Other,
}

fn kind_of(type_id: u8) -> Kind {
    let numbers = |scalar, components| Kind::Numbers {
        scalar,
        components,
        matrix: false,
        quaternion: false,
    };
    let matrix = |components| Kind::Numbers {
        scalar: Scalar::F64,
        components,
        matrix: true,
        quaternion: false,
    };
    let quaternion = |scalar| Kind::Numbers {
        scalar,
        components: 4,
        matrix: false,
        quaternion: true,
    };
    match type_id {
        1 | 2 => numbers(Scalar::U8, 1),
        3 => numbers(Scalar::I32, 1),
        4 => numbers(Scalar::U32, 1),
        5 => numbers(Scalar::I64, 1),
        6 => numbers(Scalar::U64, 1),
        7 => numbers(Scalar::F16, 1),
        8 => numbers(Scalar::F32, 1),
        9 | 56 => numbers(Scalar::F64, 1),
        10 => Kind::String,
        11 => Kind::Token,
        12 => Kind::AssetPath,
        13 => matrix(4),
        14 => matrix(9),
        15 => matrix(16),
        16 => quaternion(Scalar::F64),
        17 => quaternion(Scalar::F32),
        18 => quaternion(Scalar::F16),
        19 => numbers(Scalar::F64, 2),
        20 => numbers(Scalar::F32, 2),
        21 => numbers(Scalar::F16, 2),
        22 => numbers(Scalar::I32, 2),
        23 => numbers(Scalar::F64, 3),
        24 => numbers(Scalar::F32, 3),
        25 => numbers(Scalar::F16, 3),
        26 => numbers(Scalar::I32, 3),
        27 => numbers(Scalar::F64, 4),
        28 => numbers(Scalar::F32, 4),
        29 => numbers(Scalar::F16, 4),
        30 => numbers(Scalar::I32, 4),
        34 => Kind::PathListOp,
        35 => Kind::ReferenceListOp,
        41 => Kind::TokenVector,
        42 => Kind::Specifier,
        44 => Kind::Variability,
        46 => Kind::TimeSamples,
        47 => Kind::Payload,
        48 => Kind::DoubleVector,
        50 => Kind::StringVector,
        55 => Kind::PayloadListOp,
        _ => Kind::Other,
    }
}

/// IEEE 754 half to single precision.
fn half_to_f32(bits: u16) -> f32 {
    let sign = u32::from(bits >> 15) << 31;
    let exponent = u32::from((bits >> 10) & 0x1f);
    let mantissa = u32::from(bits & 0x3ff);
    let value = match (exponent, mantissa) {
        (0, 0) => sign,
        (0, m) => {
            // Subnormal: value = m * 2^-24.
            let magnitude = m as f32 * f32::from_bits(0x3380_0000);
            return if sign != 0 { -magnitude } else { magnitude };
        }
        (0x1f, m) => sign | 0x7f80_0000 | (m << 13),
        (e, m) => sign | ((e + 112) << 23) | (m << 13),
    };
    f32::from_bits(value)
}

impl<'a> CrateReader<'a> {
    /// Decodes a value rep; `what` names it in errors.
    pub(super) fn value(&self, rep: u64, what: &str, depth: usize) -> Result<Value> {
        let type_id = ((rep >> 48) & 0xff) as u8;
        let payload = rep & PAYLOAD_MASK;
        let array = rep & ARRAY_BIT != 0;
        let inlined = rep & INLINED_BIT != 0;
        let compressed = rep & COMPRESSED_BIT != 0;
        let text = |data: Vec<String>, array| Value::Text { array, data };
        match kind_of(type_id) {
            Kind::Numbers {
                scalar,
                components,
                matrix,
                quaternion,
            } => {
                let mut data = if array {
                    self.numeric_array(payload, scalar, components, compressed, what)?
                } else if inlined {
                    inline_numbers(payload as u32, scalar, components, matrix)
                } else {
                    self.numbers_at(payload, components as u64, scalar, what)?
                };
                if quaternion {
                    // Stored imaginary first, real last; USD text writes real first.
                    for q in data.chunks_exact_mut(4) {
                        q.rotate_right(1);
                    }
                }
                Ok(Value::Numbers {
                    components,
                    array,
                    data,
                })
            }
            Kind::Token if array => {
                let indices = self.raw_index_array(payload, what)?;
                let tokens = indices
                    .into_iter()
                    .map(|i| self.token(i, payload))
                    .collect::<Result<Vec<_>>>()?;
                Ok(text(tokens, true))
            }
            Kind::String if array => {
                let indices = self.raw_index_array(payload, what)?;
                let strings = indices
                    .into_iter()
                    .map(|i| self.string(i, payload))
                    .collect::<Result<Vec<_>>>()?;
                Ok(text(strings, true))
            }
            Kind::Token | Kind::AssetPath if inlined => {
                Ok(text(vec![self.token(payload, payload)?], false))
            }
            Kind::String if inlined => Ok(text(vec![self.string(payload, payload)?], false)),
            Kind::TokenVector => {
                let tokens = self
                    .index_vector(payload, what)?
                    .into_iter()
                    .map(|i| self.token(i, payload))
                    .collect::<Result<Vec<_>>>()?;
                Ok(text(tokens, true))
            }
            Kind::StringVector => {
                let strings = self
                    .index_vector(payload, what)?
                    .into_iter()
                    .map(|i| self.string(i, payload))
                    .collect::<Result<Vec<_>>>()?;
                Ok(text(strings, true))
            }
            Kind::DoubleVector => {
                let count = self.u64_at(payload, what)?;
                let data = self.numbers_at(payload + 8, count, Scalar::F64, what)?;
                Ok(Value::Numbers {
                    components: 1,
                    array: true,
                    data,
                })
            }
            Kind::PathListOp => Ok(Value::Arcs(self.list_op(payload, ArcItem::Path, what)?)),
            Kind::ReferenceListOp => Ok(Value::Arcs(self.list_op(
                payload,
                ArcItem::Reference,
                what,
            )?)),
            Kind::PayloadListOp => Ok(Value::Arcs(self.list_op(
                payload,
                ArcItem::Payload,
                what,
            )?)),
            Kind::Payload => {
                let (target, _) = self.arc_item(payload, ArcItem::Payload, what)?;
                Ok(Value::Arcs(vec![target]))
            }
            Kind::Specifier => Ok(Value::Numbers {
                components: 1,
                array: false,
                data: vec![(payload & 0xffff_ffff) as f64],
            }),
            Kind::TimeSamples if depth > 0 => {
                Err(self.error(payload, format!("{what}: time samples inside time samples")))
            }
            _ => Ok(Value::Other),
        }
    }

    /// The items of a composition list op (OpenUSD's `SdfListOp` as the
    /// crate stores it: a header byte, then each list it flags as `u64
    /// count` and the items). Strongest first: prepended, explicit, added,
    /// appended; deleted and ordered items are read past, as the text
    /// reader skips `delete` and `reorder` lists.
    fn list_op(&self, offset: u64, item: ArcItem, what: &str) -> Result<Vec<ArcTarget>> {
        let header = self.slice(offset, 1, what)?[0];
        let mut at = offset + 1;
        // In the order the crate writes them.
        let mut lists: [(u8, Vec<ArcTarget>); 6] = [
            (LIST_OP_EXPLICIT, Vec::new()),
            (LIST_OP_ADDED, Vec::new()),
            (LIST_OP_PREPENDED, Vec::new()),
            (LIST_OP_APPENDED, Vec::new()),
            (LIST_OP_DELETED, Vec::new()),
            (LIST_OP_ORDERED, Vec::new()),
        ];
        for (bit, items) in &mut lists {
            if header & *bit == 0 {
                continue;
            }
            let count = self.u64_at(at, what)?;
            at += 8;
            // Every item takes at least `min_size` bytes: a count the rest
            // of the file cannot hold is refused before anything is read.
            let room = (self.bytes.len() as u64).saturating_sub(at);
            if count
                .checked_mul(item.min_size(self.version))
                .is_none_or(|n| n > room)
            {
                return Err(self.error(
                    at - 8,
                    format!("{what}: {count} list items do not fit in the file"),
                ));
            }
            for _ in 0..count {
                let (target, next) = self.arc_item(at, item, what)?;
                items.push(target);
                at = next;
            }
        }
        let [explicit, added, prepended, appended, _, _] = lists.map(|(_, items)| items);
        Ok(prepended
            .into_iter()
            .chain(explicit)
            .chain(added)
            .chain(appended)
            .collect())
    }

    /// One item of a list op at `offset`, and the offset after it.
    fn arc_item(&self, offset: u64, item: ArcItem, what: &str) -> Result<(ArcTarget, u64)> {
        let path_at = |at: u64| -> Result<Option<String>> {
            let index = self.u32_at(at, what)?;
            self.arc_path(index, at, what)
        };
        match item {
            ArcItem::Path => Ok((
                ArcTarget {
                    asset: None,
                    prim_path: path_at(offset)?,
                    offset: LayerOffset::default(),
                },
                offset + 4,
            )),
            ArcItem::Reference | ArcItem::Payload => {
                let asset = self.string(u64::from(self.u32_at(offset, what)?), offset)?;
                let prim_path = path_at(offset + 4)?;
                // The layer offset: two doubles, offset then scale.
                let mut next = offset + 8;
                let mut layer_offset = LayerOffset::default();
                if item == ArcItem::Reference || self.at_least((0, 8, 0)) {
                    let bytes = self.slice(next, 16, what)?;
                    let double = |b: &[u8]| -> f64 {
                        let mut raw = [0u8; 8];
                        raw.copy_from_slice(b);
                        f64::from_le_bytes(raw)
                    };
                    layer_offset = LayerOffset {
                        offset: double(&bytes[..8]),
                        scale: double(&bytes[8..16]),
                    };
                    if !(layer_offset.offset.is_finite() && layer_offset.scale.is_finite()) {
                        return Err(
                            self.error(next, format!("{what}: a layer offset is not finite"))
                        );
                    }
                    next += 16;
                }
                if item == ArcItem::Reference {
                    let custom_data = self.u64_at(next, what)?;
                    if custom_data != 0 {
                        return Err(self.error(
                            next,
                            format!("{what}: a reference with customData is not read"),
                        ));
                    }
                    next += 8;
                }
                let target = ArcTarget {
                    asset: (!asset.is_empty()).then_some(asset),
                    prim_path,
                    offset: layer_offset,
                };
                Ok((target, next))
            }
        }
    }

    /// The prim path an arc names by path index; `None` for the empty path
    /// (the target layer's `defaultPrim`).
    fn arc_path(&self, index: u32, at: u64, what: &str) -> Result<Option<String>> {
        // The empty path has an index but no place in the path tree.
        match self.paths.get(index as usize) {
            Some(Some(entry)) => Ok(Some(entry.text.clone())),
            Some(None) => Ok(None),
            None => Err(self.error(at, format!("{what}: path index {index} out of range"))),
        }
    }

    /// An array of u32 indices stored raw (token and string arrays).
    fn raw_index_array(&self, payload: u64, what: &str) -> Result<Vec<u64>> {
        if payload == 0 {
            return Ok(Vec::new());
        }
        let (count, data_start) = self.array_header(payload, what)?;
        let data = self.numbers_at(data_start, count, Scalar::U32, what)?;
        Ok(data.into_iter().map(|x| x as u64).collect())
    }

    /// Element count and the offset after it, for the file's version.
    fn array_header(&self, payload: u64, what: &str) -> Result<(u64, u64)> {
        let mut at = payload;
        if !self.at_least((0, 5, 0)) {
            at += 4; // rank, always 1
        }
        if self.at_least((0, 7, 0)) {
            Ok((self.u64_at(at, what)?, at + 8))
        } else {
            Ok((u64::from(self.u32_at(at, what)?), at + 4))
        }
    }

    fn numeric_array(
        &self,
        payload: u64,
        scalar: Scalar,
        components: usize,
        compressed: bool,
        what: &str,
    ) -> Result<Vec<f64>> {
        if payload == 0 {
            return Ok(Vec::new());
        }
        let (count, data_start) = self.array_header(payload, what)?;
        let integral = matches!(
            scalar,
            Scalar::I32 | Scalar::U32 | Scalar::I64 | Scalar::U64
        );
        let floating = matches!(scalar, Scalar::F16 | Scalar::F32 | Scalar::F64);
        let may_compress = components == 1
            && compressed
            && count >= MIN_COMPRESSED_ARRAY_SIZE
            && ((integral && self.at_least((0, 5, 0))) || (floating && self.at_least((0, 6, 0))));
        if !may_compress {
            let values = count
                .checked_mul(components as u64)
                .ok_or_else(|| self.error(payload, format!("{what}: count {count} too large")))?;
            return self.numbers_at(data_start, values, scalar, what);
        }
        let end = self.bytes.len() as u64;
        if integral {
            let wide = matches!(scalar, Scalar::I64 | Scalar::U64);
            let (ints, _) = self.compressed_ints(data_start, end, count, wide, what)?;
            return Ok(ints
                .into_iter()
                .map(|i| match scalar {
                    Scalar::U32 => f64::from(i as u32),
                    Scalar::U64 => i as u64 as f64,
                    _ => i as f64,
                })
                .collect());
        }
        let code = self.slice(data_start, 1, what)?[0];
        match code {
            b'i' => {
                let (ints, _) = self.compressed_ints(data_start + 1, end, count, false, what)?;
                Ok(ints.into_iter().map(|i| f64::from(i as i32)).collect())
            }
            b't' => {
                let table_size = u64::from(self.u32_at(data_start + 1, what)?);
                let table = self.numbers_at(data_start + 5, table_size, scalar, what)?;
                let after = data_start + 5 + table_size * scalar.size();
                let (indices, _) = self.compressed_ints(after, end, count, false, what)?;
                indices
                    .into_iter()
                    .map(|i| {
                        table.get(i as u32 as usize).copied().ok_or_else(|| {
                            self.error(after, format!("{what}: lookup index {i} out of range"))
                        })
                    })
                    .collect()
            }
            other => Err(self.error(
                data_start,
                format!("{what}: unknown compressed array code {other}"),
            )),
        }
    }

    /// `(time codes, value reps)` of a TimeSamples rep.
    pub(super) fn time_samples(
        &self,
        rep: u64,
        what: &str,
        defer: bool,
    ) -> Result<Vec<(f64, Value)>> {
        let at = rep & PAYLOAD_MASK;
        let jump = |offset: u64| -> Result<u64> {
            let relative = self.u64_at(offset, what)? as i64;
            offset
                .checked_add_signed(relative)
                .filter(|&target| target < self.bytes.len() as u64)
                .ok_or_else(|| {
                    self.error(
                        offset,
                        format!("{what}: time samples jump {relative} leaves the file"),
                    )
                })
        };
        let times_at = jump(at)?;
        let times_rep = self.u64_at(times_at, what)?;
        let times = match self.value(times_rep, what, 1)? {
            Value::Numbers {
                components: 1,
                data,
                ..
            } => data,
            _ => {
                return Err(self.error(
                    times_at,
                    format!("{what}: time sample times are not doubles"),
                ))
            }
        };
        let values_at = jump(times_at + 8)?;
        let count = self.u64_at(values_at, what)?;
        if count != times.len() as u64 {
            return Err(self.error(
                values_at,
                format!("{what}: {count} values for {} time samples", times.len()),
            ));
        }
        let raw = self.slice(values_at + 8, count * 8, what)?;
        let mut samples = Vec::with_capacity(times.len());
        for (time, chunk) in times.into_iter().zip(raw.chunks_exact(8)) {
            let mut bytes = [0u8; 8];
            bytes.copy_from_slice(chunk);
            let rep = u64::from_le_bytes(bytes);
            let value = if defer && rep & ARRAY_BIT != 0 && rep & INLINED_BIT == 0 {
                Value::Deferred(rep)
            } else {
                self.value(rep, what, 1)?
            };
            samples.push((time, value));
        }
        Ok(samples)
    }
}

/// Inlined numbers: 32-bit scalars as themselves, doubles as f32, 64-bit
/// ints as 32-bit, vectors as one i8 per component, matrices as an i8
/// diagonal.
fn inline_numbers(payload: u32, scalar: Scalar, components: usize, matrix: bool) -> Vec<f64> {
    let bytes = payload.to_le_bytes();
    if matrix {
        let n = match components {
            4 => 2,
            9 => 3,
            _ => 4,
        };
        let mut data = vec![0.0; components];
        for i in 0..n {
            data[i * n + i] = f64::from(bytes[i] as i8);
        }
        return data;
    }
    if components > 1 {
        return bytes
            .iter()
            .take(components)
            .map(|&b| f64::from(b as i8))
            .collect();
    }
    let value = match scalar {
        Scalar::U8 => f64::from(bytes[0]),
        Scalar::I32 | Scalar::I64 => f64::from(payload as i32),
        Scalar::U32 | Scalar::U64 => f64::from(payload),
        Scalar::F16 => f64::from(half_to_f32(payload as u16)),
        Scalar::F32 | Scalar::F64 => f64::from(f32::from_bits(payload)),
    };
    vec![value]
}
