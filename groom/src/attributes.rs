//! Named per-vertex and per-strand attributes.

/// What an attribute has one value for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scope {
    Vertex,
    Strand,
}

/// The values of an attribute, one element per vertex or per strand.
#[derive(Debug, Clone, PartialEq)]
pub enum AttributeValues {
    Float(Vec<f32>),
    Vec2(Vec<[f32; 2]>),
    Vec3(Vec<[f32; 3]>),
    Int(Vec<i32>),
}

impl AttributeValues {
    /// The elements in `ranges`, in order (ranges past the end are cut).
    pub fn select(&self, ranges: &[std::ops::Range<usize>]) -> AttributeValues {
        fn pick<T: Copy>(values: &[T], ranges: &[std::ops::Range<usize>]) -> Vec<T> {
            ranges
                .iter()
                .flat_map(|r| {
                    let end = r.end.min(values.len());
                    values[r.start.min(end)..end].iter().copied()
                })
                .collect()
        }
        match self {
            AttributeValues::Float(v) => AttributeValues::Float(pick(v, ranges)),
            AttributeValues::Vec2(v) => AttributeValues::Vec2(pick(v, ranges)),
            AttributeValues::Vec3(v) => AttributeValues::Vec3(pick(v, ranges)),
            AttributeValues::Int(v) => AttributeValues::Int(pick(v, ranges)),
        }
    }

    /// Number of elements (not components).
    pub fn len(&self) -> usize {
        match self {
            AttributeValues::Float(v) => v.len(),
            AttributeValues::Vec2(v) => v.len(),
            AttributeValues::Vec3(v) => v.len(),
            AttributeValues::Int(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Components per element: 1, 2 or 3.
    pub fn components(&self) -> usize {
        match self {
            AttributeValues::Float(_) | AttributeValues::Int(_) => 1,
            AttributeValues::Vec2(_) => 2,
            AttributeValues::Vec3(_) => 3,
        }
    }

    /// Type name as `inspect` prints it.
    pub fn type_name(&self) -> &'static str {
        match self {
            AttributeValues::Float(_) => "float",
            AttributeValues::Vec2(_) => "vec2",
            AttributeValues::Vec3(_) => "vec3",
            AttributeValues::Int(_) => "int",
        }
    }

    /// Every component as f32, element after element (ints converted).
    pub fn to_f32_flat(&self) -> Vec<f32> {
        match self {
            AttributeValues::Float(v) => v.clone(),
            AttributeValues::Vec2(v) => v.iter().flatten().copied().collect(),
            AttributeValues::Vec3(v) => v.iter().flatten().copied().collect(),
            AttributeValues::Int(v) => v.iter().map(|&i| i as f32).collect(),
        }
    }

    /// Index of the first component that is not finite, if any.
    pub fn first_non_finite(&self) -> Option<usize> {
        let elements: Box<dyn Iterator<Item = bool>> = match self {
            AttributeValues::Float(v) => Box::new(v.iter().map(|x| x.is_finite())),
            AttributeValues::Vec2(v) => Box::new(v.iter().map(|x| x.iter().all(|c| c.is_finite()))),
            AttributeValues::Vec3(v) => Box::new(v.iter().map(|x| x.iter().all(|c| c.is_finite()))),
            AttributeValues::Int(_) => return None,
        };
        elements.enumerate().find(|(_, ok)| !ok).map(|(i, _)| i)
    }

    /// Multiplies every float component by `factor` (ints stay).
    pub fn scale(&mut self, factor: f32) {
        match self {
            AttributeValues::Float(v) => v.iter_mut().for_each(|x| *x *= factor),
            AttributeValues::Vec2(v) => v.iter_mut().flatten().for_each(|x| *x *= factor),
            AttributeValues::Vec3(v) => v.iter_mut().flatten().for_each(|x| *x *= factor),
            AttributeValues::Int(_) => {}
        }
    }
}

/// A named attribute.
#[derive(Debug, Clone, PartialEq)]
pub struct Attribute {
    pub name: String,
    pub scope: Scope,
    pub values: AttributeValues,
}

impl Attribute {
    /// A per-vertex attribute.
    pub fn new(name: impl Into<String>, values: AttributeValues) -> Attribute {
        Attribute {
            name: name.into(),
            scope: Scope::Vertex,
            values,
        }
    }

    /// A per-strand attribute.
    pub fn per_strand(name: impl Into<String>, values: AttributeValues) -> Attribute {
        Attribute {
            name: name.into(),
            scope: Scope::Strand,
            values,
        }
    }
}
