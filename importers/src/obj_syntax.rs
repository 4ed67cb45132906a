//! The `.obj` statement syntax that the polyline importer (`obj`) and the
//! collider mesh reader (`mesh`) share: lines with `#` comments, tokens with
//! their columns, `v x y z [w]` coordinates and vertex indices (1-based,
//! negative ones relative to the vertices read so far, `i/t/n` references
//! keep the vertex index) that may refer past the vertices read so far.

use crate::{ImportError, Place};
use std::path::Path;

/// One non-empty line of an `.obj` file: its keyword and the tokens after it.
pub(crate) struct Statement<'a> {
    path: &'a Path,
    pub(crate) line: usize,
    /// The line without its comment.
    text: &'a str,
    pub(crate) keyword: &'a str,
    tokens: Tokens<'a>,
}

/// The statements of `bytes`, line by line; a line that is not UTF-8 is an
/// error.
pub(crate) fn statements<'a>(
    path: &'a Path,
    bytes: &'a [u8],
) -> impl Iterator<Item = Result<Statement<'a>, ImportError>> {
    bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .filter_map(move |(line_index, raw)| {
            let line = line_index + 1;
            let text = match std::str::from_utf8(raw) {
                Ok(text) => text,
                Err(e) => {
                    return Some(Err(line_error(
                        path,
                        line,
                        e.valid_up_to() + 1,
                        "not UTF-8 text".into(),
                    )))
                }
            };
            let text = text.split('#').next().unwrap_or("");
            let mut tokens = tokens_with_columns(text);
            let (_, keyword) = tokens.next()?;
            Some(Ok(Statement {
                path,
                line,
                text,
                keyword,
                tokens,
            }))
        })
}

fn line_error(path: &Path, line: usize, column: usize, message: String) -> ImportError {
    ImportError::malformed(path, Place::Line { line, column }, message)
}

/// Why a coordinate was refused (the two readers word it differently).
pub(crate) enum BadCoordinate {
    NotANumber,
    NotFinite,
}

impl Statement<'_> {
    pub(crate) fn error(&self, column: usize, message: String) -> ImportError {
        line_error(self.path, self.line, column, message)
    }

    /// The x, y, z of a `v` statement (a w after them is ignored); `word`
    /// says what is wrong with a coordinate token.
    pub(crate) fn coordinates(
        &mut self,
        word: impl Fn(&str, BadCoordinate) -> String,
    ) -> Result<[f32; 3], ImportError> {
        let mut point = [0f32; 3];
        for (k, component) in point.iter_mut().enumerate() {
            let (column, token) = self.tokens.next().ok_or_else(|| {
                self.error(
                    self.text.len() + 1,
                    format!("vertex has {k} coordinates, expected 3"),
                )
            })?;
            *component = match token.parse::<f32>() {
                Err(_) => return Err(self.error(column, word(token, BadCoordinate::NotANumber))),
                Ok(value) if !value.is_finite() => {
                    return Err(self.error(column, word(token, BadCoordinate::NotFinite)))
                }
                Ok(value) => value,
            };
        }
        Ok(point)
    }

    /// The u and v of a `vt` statement (v is 0 when absent; a w after them
    /// is ignored).
    pub(crate) fn texture_coordinates(&mut self) -> Result<[f32; 2], ImportError> {
        let mut uv = [0f32; 2];
        for (k, component) in uv.iter_mut().enumerate() {
            let Some((column, token)) = self.tokens.next() else {
                if k == 0 {
                    return Err(
                        self.error(self.text.len() + 1, "texture coordinate has no u".into())
                    );
                }
                break;
            };
            *component = match token.parse::<f32>() {
                Ok(value) if value.is_finite() => value,
                _ => return Err(self.error(column, format!("'{token}' is not a finite number"))),
            };
        }
        Ok(uv)
    }

    /// The 0-based vertex indices of an `f` or `l` statement, given how many
    /// vertices were read so far and the largest 1-based index the reader
    /// takes; indices past the vertices read so far go to `forward`.
    pub(crate) fn vertex_indices(
        &mut self,
        vertex_count: usize,
        largest: i64,
        forward: &mut ForwardReferences,
    ) -> Result<Vec<usize>, ImportError> {
        Ok(self
            .corner_indices(vertex_count, largest, forward, None)?
            .into_iter()
            .map(|(vertex, _)| vertex)
            .collect())
    }

    /// The 0-based vertex indices of the corners of an `f` statement (`i`,
    /// `i/t`, `i/t/n`, `i//n`) and, when `textures` gives how many `vt` were
    /// read so far, their texture coordinate indices; indices past those
    /// read so far go to the forward references.
    pub(crate) fn corner_indices(
        &mut self,
        vertex_count: usize,
        largest: i64,
        vertex_forward: &mut ForwardReferences,
        mut textures: Option<(usize, &mut ForwardReferences)>,
    ) -> Result<Vec<(usize, Option<usize>)>, ImportError> {
        let mut corners = Vec::new();
        while let Some((column, token)) = self.tokens.next() {
            let mut parts = token.split('/');
            let number = parts.next().unwrap_or("");
            let value: i64 = number
                .parse()
                .map_err(|_| self.error(column, format!("'{token}' is not a vertex index")))?;
            let vertex =
                self.index(value, vertex_count, largest, column, VERTEX, vertex_forward)?;
            let texture = match (parts.next(), textures.as_mut()) {
                (None | Some(""), _) | (_, None) => None,
                (Some(number), Some((texture_count, texture_forward))) => {
                    let value: i64 = number.parse().map_err(|_| {
                        self.error(
                            column,
                            format!("'{token}' has no valid texture coordinate index"),
                        )
                    })?;
                    Some(self.index(
                        value,
                        *texture_count,
                        largest,
                        column,
                        TEXTURE,
                        texture_forward,
                    )?)
                }
            };
            corners.push((vertex, texture));
        }
        Ok(corners)
    }

    /// One 1-based (or negative, relative) index made 0-based.
    fn index(
        &self,
        value: i64,
        count: usize,
        largest: i64,
        column: usize,
        noun: &'static str,
        forward: &mut ForwardReferences,
    ) -> Result<usize, ImportError> {
        let index = if value > 0 && value <= largest {
            (value - 1) as usize
        } else if value < 0 && value.unsigned_abs() as usize <= count {
            count - value.unsigned_abs() as usize
        } else {
            let so_far = if noun == VERTEX {
                "vertices"
            } else {
                "texture coordinates"
            };
            return Err(self.error(
                column,
                format!("{noun} index {value} is out of range ({count} {so_far} so far)"),
            ));
        };
        if index >= count {
            forward.0.push(ForwardReference {
                index,
                line: self.line,
                column,
            });
        }
        Ok(index)
    }
}

const VERTEX: &str = "vertex";
const TEXTURE: &str = "texture coordinate";

/// A vertex index that refers past the vertices read so far.
struct ForwardReference {
    index: usize,
    line: usize,
    column: usize,
}

/// The forward references of a file, checked once the whole file is read.
#[derive(Default)]
pub(crate) struct ForwardReferences(Vec<ForwardReference>);

impl ForwardReferences {
    pub(crate) fn check(&self, path: &Path, vertex_count: usize) -> Result<(), ImportError> {
        self.check_as(path, vertex_count, VERTEX, "vertices")
    }

    /// [`ForwardReferences::check`] for texture coordinate (`vt`) indices.
    pub(crate) fn check_textures(&self, path: &Path, count: usize) -> Result<(), ImportError> {
        self.check_as(path, count, TEXTURE, "texture coordinates")
    }

    fn check_as(
        &self,
        path: &Path,
        count: usize,
        noun: &str,
        plural: &str,
    ) -> Result<(), ImportError> {
        match self.0.iter().find(|r| r.index >= count) {
            Some(bad) => Err(line_error(
                path,
                bad.line,
                bad.column,
                format!(
                    "{noun} index {} is out of range (the file has {count} {plural})",
                    bad.index + 1,
                ),
            )),
            None => Ok(()),
        }
    }
}

/// Whitespace-separated tokens with their 1-based columns.
struct Tokens<'a> {
    rest: &'a str,
    offset: usize,
}

fn tokens_with_columns(text: &str) -> Tokens<'_> {
    Tokens {
        rest: text,
        offset: 0,
    }
}

impl<'a> Iterator for Tokens<'a> {
    type Item = (usize, &'a str);

    fn next(&mut self) -> Option<Self::Item> {
        let trimmed = self.rest.trim_start();
        self.offset += self.rest.len() - trimmed.len();
        if trimmed.is_empty() {
            return None;
        }
        let end = trimmed
            .find(|c: char| c.is_whitespace())
            .unwrap_or(trimmed.len());
        let token = &trimmed[..end];
        let column = self.offset + 1;
        self.offset += end;
        self.rest = &trimmed[end..];
        Some((column, token))
    }
}
