//! Accessors read by hand rather than by the crate's reader, so that every
//! range is checked against the buffer before anything is allocated or read.

use super::document::Document;
use crate::ImportError;
use gltf::json;
use groom::AttributeValues;
use json::accessor::{ComponentType, Type};

/// An accessor whose component type and element type are known glTF values.
pub(super) struct Accessor<'d> {
    pub index: usize,
    pub json: &'d json::Accessor,
    pub component: ComponentType,
    pub kind: Type,
}

impl Accessor<'_> {
    pub fn place(&self) -> String {
        format!("/accessors/{}", self.index)
    }

    pub fn count(&self) -> u64 {
        self.json.count.0
    }

    fn element_size(&self) -> usize {
        self.component.size() * self.kind.multiplicity()
    }
}

impl Document<'_> {
    /// Accessor `index`, referenced from the JSON pointer `from`.
    pub fn accessor(
        &self,
        index: json::Index<json::Accessor>,
        from: impl FnOnce() -> String,
    ) -> Result<Accessor<'_>, ImportError> {
        let index = index.value();
        let json = self.get(&self.root.accessors, index, "accessor", from)?;
        let place = || format!("/accessors/{index}");
        let component = self
            .valid(&json.component_type, "componentType", || {
                format!("{}/componentType", place())
            })?
            .0;
        let kind = self.valid(&json.type_, "accessor type", || format!("{}/type", place()))?;
        Ok(Accessor {
            index,
            json,
            component,
            kind,
        })
    }

    /// The bytes of each element of an accessor, after checking the whole
    /// range lies inside its buffer view and buffer.
    fn elements<'b>(&'b self, accessor: &Accessor) -> Result<Vec<&'b [u8]>, ImportError> {
        let (data, start, stride) = self.element_range(accessor)?;
        let element_size = accessor.element_size();
        let count = accessor.count();
        // Decoded elements take at least a pointer each.
        let per_element = element_size.max(std::mem::size_of::<&[u8]>()) as u64;
        self.charge(count.saturating_mul(per_element), || accessor.place())?;
        // `element_range` checked both bounds lie within the buffer.
        let count = count as usize;
        Ok((0..count)
            .map(|k| &data[start + k * stride..start + k * stride + element_size])
            .collect())
    }

    /// The buffer, start offset and stride of an accessor's elements, after
    /// checking the whole range lies inside its buffer view and buffer;
    /// reads none of the elements.
    fn element_range<'b>(
        &'b self,
        accessor: &Accessor,
    ) -> Result<(&'b [u8], usize, usize), ImportError> {
        let place = accessor.place();
        if accessor.json.sparse.is_some() {
            return Err(self.error(place, "sparse accessors are not supported"));
        }
        let Some(view_index) = accessor.json.buffer_view else {
            return Err(self.error(place, "accessor without bufferView"));
        };
        let view_index = view_index.value();
        let view = self.get(&self.root.buffer_views, view_index, "bufferView", || {
            format!("{place}/bufferView")
        })?;
        let data = self.buffer(view.buffer.value(), || {
            format!("/bufferViews/{view_index}/buffer")
        })?;
        let element_size = accessor.element_size();
        let stride = view
            .byte_stride
            .map_or(element_size, |s| s.0)
            .max(element_size);
        let count = accessor.count();
        let view_offset = view.byte_offset.map_or(0, |o| o.0);
        let view_end = view_offset.checked_add(view.byte_length.0);
        let start = view_offset.checked_add(accessor.json.byte_offset.map_or(0, |o| o.0));
        let span = match count.checked_sub(1) {
            None => Some(0),
            Some(n) => n
                .checked_mul(stride as u64)
                .and_then(|s| s.checked_add(element_size as u64)),
        };
        let end = match (start, span) {
            (Some(start), Some(span)) => start.checked_add(span),
            _ => None,
        };
        match (start, end, view_end) {
            (Some(start), Some(end), Some(view_end))
                if end <= view_end && end <= data.len() as u64 =>
            {
                // Both bounds are within the buffer, so they fit in usize.
                Ok((data, start as usize, stride))
            }
            _ => Err(self.error(
                place,
                format!(
                    "{count} elements of {element_size} bytes (stride {stride}) do not fit in bufferView {view_index} ({} bytes at offset {view_offset})",
                    view.byte_length.0,
                ),
            )),
        }
    }

    pub fn floats(&self, accessor: &Accessor, kind: Type) -> Result<Vec<f32>, ImportError> {
        let place = accessor.place();
        self.float_type(accessor, kind)?;
        let elements = self.elements(accessor)?;
        let mut values = Vec::with_capacity(elements.len() * kind.multiplicity());
        for element in elements {
            for c in element.chunks_exact(4) {
                let v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
                if !v.is_finite() {
                    return Err(self.error(place, format!("value {v} is not finite")));
                }
                values.push(v);
            }
        }
        Ok(values)
    }

    /// What [`Document::floats`] checks before decoding (the type and that
    /// the elements lie in their buffer), without reading the values: a
    /// value that is not finite, or a reference past the decode budget, is
    /// found only when the accessor is decoded.
    pub fn check_floats(&self, accessor: &Accessor, kind: Type) -> Result<(), ImportError> {
        self.float_type(accessor, kind)?;
        self.element_range(accessor).map(|_| ())
    }

    fn float_type(&self, accessor: &Accessor, kind: Type) -> Result<(), ImportError> {
        if accessor.component != ComponentType::F32 || accessor.kind != kind {
            return Err(self.error(
                accessor.place(),
                format!(
                    "expected {kind:?} of FLOAT, found {:?} of {:?}",
                    accessor.kind, accessor.component
                ),
            ));
        }
        Ok(())
    }

    pub fn vec3(&self, accessor: &Accessor) -> Result<Vec<[f32; 3]>, ImportError> {
        let flat = self.floats(accessor, Type::Vec3)?;
        Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    pub fn vec2(&self, accessor: &Accessor) -> Result<Vec<[f32; 2]>, ImportError> {
        let flat = self.floats(accessor, Type::Vec2)?;
        Ok(flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
    }

    pub fn indices(&self, accessor: &Accessor) -> Result<Vec<usize>, ImportError> {
        let values = self
            .scalar_integers(accessor)?
            .ok_or_else(|| self.error(accessor.place(), "indices are not unsigned integers"))?;
        Ok(values.into_iter().map(|v| v as usize).collect())
    }

    /// SCALAR unsigned integer accessors as u32; `None` for other types.
    fn scalar_integers(&self, accessor: &Accessor) -> Result<Option<Vec<u32>>, ImportError> {
        if accessor.kind != Type::Scalar || accessor.json.normalized {
            return Ok(None);
        }
        let decode: fn(&[u8]) -> u32 = match accessor.component {
            ComponentType::U8 => |b| b[0] as u32,
            ComponentType::U16 => |b| u16::from_le_bytes([b[0], b[1]]) as u32,
            ComponentType::U32 => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            _ => return Ok(None),
        };
        Ok(Some(
            self.elements(accessor)?.into_iter().map(decode).collect(),
        ))
    }

    /// SCALAR integer accessors as i32; `None` for other types.
    fn signed_integers(&self, accessor: &Accessor) -> Result<Option<Vec<i32>>, ImportError> {
        if accessor.kind != Type::Scalar || accessor.json.normalized {
            return Ok(None);
        }
        let decode: fn(&[u8]) -> i32 = match accessor.component {
            ComponentType::U8 => |b| b[0] as i32,
            ComponentType::I8 => |b| b[0] as i8 as i32,
            ComponentType::U16 => |b| u16::from_le_bytes([b[0], b[1]]) as i32,
            ComponentType::I16 => |b| i16::from_le_bytes([b[0], b[1]]) as i32,
            // Wraps like the exporter's `as`: groombake writes no u32.
            ComponentType::U32 => |b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            ComponentType::F32 => return Ok(None),
        };
        Ok(Some(
            self.elements(accessor)?.into_iter().map(decode).collect(),
        ))
    }

    /// A custom attribute; `None` for types the groom has no place for.
    pub fn attribute(&self, accessor: &Accessor) -> Result<Option<AttributeValues>, ImportError> {
        if accessor.component == ComponentType::F32 {
            return Ok(match accessor.kind {
                Type::Scalar => Some(AttributeValues::Float(self.floats(accessor, Type::Scalar)?)),
                Type::Vec2 => Some(AttributeValues::Vec2(self.vec2(accessor)?)),
                Type::Vec3 => Some(AttributeValues::Vec3(self.vec3(accessor)?)),
                _ => None,
            });
        }
        Ok(self.signed_integers(accessor)?.map(AttributeValues::Int))
    }

    /// 32-bit integers stored as a VEC2 of UNSIGNED_SHORT (low half first),
    /// as earlier groombake versions wrote them; `None` for other accessor types.
    pub fn split_integers(
        &self,
        accessor: &Accessor,
    ) -> Result<Option<AttributeValues>, ImportError> {
        if accessor.component != ComponentType::U16
            || accessor.kind != Type::Vec2
            || accessor.json.normalized
        {
            return Ok(None);
        }
        let values = self
            .elements(accessor)?
            .into_iter()
            .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Ok(Some(AttributeValues::Int(values)))
    }
}
