//! A Python dict as TOML text, one value per line, with the key path of
//! every line: the timeline then goes through the very parser and checks a
//! file does, and an error's line maps back to the key path in the dict
//! (`stage[1].duration`).
//!
//! Hand-written rather than a TOML serializer because the line-to-key map
//! is the point: top-level tables become `[name]` / `[[name]]` headers and
//! every leaf one `dotted.key = value` line beneath them.
//!
//! Nesting is bounded ([`MAX_DEPTH`]) and a list or dict that contains
//! itself is refused: either would otherwise recurse until the
//! interpreter's stack overflows.

use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// Lists and dicts nested deeper than this are refused (a timeline nests
/// four: `stage[0].motion.keys[1]`; the TOML parser stops at 80).
pub const MAX_DEPTH: usize = 64;

/// The containers from the top of the dict down to the value being
/// written: their depth, and their identities to find a cycle.
#[derive(Default)]
struct Ancestors(Vec<usize>);

impl Ancestors {
    /// Enters `value` (a list, tuple or dict) at `path`, or refuses it.
    fn enter(&mut self, value: &Bound<'_, PyAny>, path: &str) -> PyResult<()> {
        let id = value.as_ptr() as usize;
        if self.0.contains(&id) {
            return Err(bad(path, "the value contains itself (a cycle)"));
        }
        if self.0.len() >= MAX_DEPTH {
            return Err(bad(
                path,
                &format!("lists and dicts nested more than {MAX_DEPTH} deep"),
            ));
        }
        self.0.push(id);
        Ok(())
    }

    fn leave(&mut self) {
        self.0.pop();
    }
}

pub struct Document {
    pub text: String,
    /// The key path of each line (index 0 = line 1).
    paths: Vec<String>,
}

fn bad(path: &str, message: &str) -> PyErr {
    super::BadInput::new_err(format!("<dict>: {path}: {message}"))
}

/// A key as TOML writes it: bare when it can be.
fn key(name: &str) -> String {
    let bare = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        name.to_string()
    } else {
        quoted(name)
    }
}

/// A TOML basic string (JSON's escapes are TOML's).
fn quoted(text: &str) -> String {
    serde_json::to_string(text).unwrap_or_else(|_| "\"\"".into())
}

fn is_table(value: &Bound<'_, PyAny>) -> bool {
    value.is_instance_of::<PyDict>()
}

fn items<'py>(value: &Bound<'py, PyAny>) -> Option<Vec<Bound<'py, PyAny>>> {
    if let Ok(list) = value.cast::<PyList>() {
        return Some(list.iter().collect());
    }
    if let Ok(tuple) = value.cast::<PyTuple>() {
        return Some(tuple.iter().collect());
    }
    None
}

fn dict_entries<'py>(
    dict: &Bound<'py, PyDict>,
    path: &str,
) -> PyResult<Vec<(String, Bound<'py, PyAny>)>> {
    dict.iter()
        .map(|(k, v)| {
            let k: String = k.extract().map_err(|_| bad(path, "keys must be strings"))?;
            Ok((k, v))
        })
        .collect()
}

fn join(path: &str, name: &str) -> String {
    if path.is_empty() {
        name.to_string()
    } else {
        format!("{path}.{name}")
    }
}

/// A value written inline (on one line).
fn inline(value: &Bound<'_, PyAny>, path: &str, up: &mut Ancestors) -> PyResult<String> {
    if value.is_none() {
        return Err(bad(path, "None is not a value (leave the key out)"));
    }
    if value.is_instance_of::<PyBool>() {
        return Ok(if value.extract::<bool>()? {
            "true"
        } else {
            "false"
        }
        .into());
    }
    if value.is_instance_of::<PyInt>() {
        let i: i64 = value
            .extract()
            .map_err(|_| bad(path, "integer out of range"))?;
        return Ok(i.to_string());
    }
    // numpy scalars and arrays: through their Python form (an array has
    // `__float__` too, which fails for more than one element).
    if !value.is_instance_of::<PyFloat>()
        && !value.is_instance_of::<PyString>()
        && items(value).is_none()
        && !is_table(value)
        && value.hasattr("tolist")?
    {
        up.enter(value, path)?;
        let result = inline(&value.call_method0("tolist")?, path, up);
        up.leave();
        return result;
    }
    if value.is_instance_of::<PyFloat>()
        || value.hasattr("__float__")?
            && !value.is_instance_of::<PyString>()
            && items(value).is_none()
            && !is_table(value)
    {
        let f: f64 = value
            .extract()
            .or_else(|_| value.call_method0("__float__")?.extract())?;
        return Ok(if f.is_nan() {
            "nan".into()
        } else if f.is_infinite() {
            if f > 0.0 {
                "inf".into()
            } else {
                "-inf".into()
            }
        } else {
            // `{:?}` keeps a decimal point or exponent: TOML reads a float.
            format!("{f:?}")
        });
    }
    if let Ok(s) = value.cast::<PyString>() {
        return Ok(quoted(&s.to_cow()?));
    }
    if let Some(list) = items(value) {
        up.enter(value, path)?;
        let parts = list
            .iter()
            .enumerate()
            .map(|(i, v)| inline(v, &format!("{path}[{i}]"), up))
            .collect::<PyResult<Vec<_>>>()?;
        up.leave();
        return Ok(format!("[{}]", parts.join(", ")));
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        up.enter(value, path)?;
        let parts = dict_entries(dict, path)?
            .iter()
            .map(|(k, v)| Ok(format!("{} = {}", key(k), inline(v, &join(path, k), up)?)))
            .collect::<PyResult<Vec<_>>>()?;
        up.leave();
        return Ok(format!("{{ {} }}", parts.join(", ")));
    }
    Err(bad(
        path,
        &format!("a {} is not a TOML value", value.get_type().name()?),
    ))
}

/// The items of a non-empty list of dicts (an array of tables).
fn table_list<'py>(value: &Bound<'py, PyAny>) -> Option<Vec<Bound<'py, PyAny>>> {
    items(value).filter(|l| !l.is_empty() && l.iter().all(is_table))
}

impl Document {
    fn line(&mut self, text: String, path: String) {
        self.text.push_str(&text);
        self.text.push('\n');
        self.paths.push(path);
    }

    /// The leaves of a table as `dotted.key = value` lines.
    fn leaves(
        &mut self,
        dict: &Bound<'_, PyDict>,
        prefix: &str,
        path: &str,
        up: &mut Ancestors,
    ) -> PyResult<()> {
        up.enter(dict.as_any(), path)?;
        for (k, v) in dict_entries(dict, path)? {
            let key_path = join(path, &k);
            let dotted = if prefix.is_empty() {
                key(&k)
            } else {
                format!("{prefix}.{}", key(&k))
            };
            match v.cast::<PyDict>() {
                Ok(sub) if !sub.is_empty() => self.leaves(sub, &dotted, &key_path, up)?,
                _ => {
                    let value = inline(&v, &key_path, up)?;
                    self.line(format!("{dotted} = {value}"), key_path);
                }
            }
        }
        up.leave();
        Ok(())
    }

    pub fn from_dict(dict: &Bound<'_, PyDict>) -> PyResult<Document> {
        let mut document = Document {
            text: String::new(),
            paths: Vec::new(),
        };
        // Line 1 stands for the document: errors about keys that are not
        // there (span 0..0) point at it.
        document.line(
            "# a timeline from a Python dict".into(),
            "(top level)".into(),
        );
        let mut up = Ancestors::default();
        up.enter(dict.as_any(), "(top level)")?;
        let entries = dict_entries(dict, "")?;
        // Plain values first: TOML puts them before any table header.
        for (k, v) in &entries {
            if !is_table(v) && table_list(v).is_none() {
                let value = inline(v, k, &mut up)?;
                document.line(format!("{} = {value}", key(k)), k.clone());
            }
        }
        for (k, v) in &entries {
            if let Ok(table) = v.cast::<PyDict>() {
                document.line(format!("[{}]", key(k)), k.clone());
                document.leaves(table, "", k, &mut up)?;
            } else if let Some(list) = table_list(v) {
                up.enter(v, k)?;
                for (i, item) in list.iter().enumerate() {
                    let path = format!("{k}[{i}]");
                    document.line(format!("[[{}]]", key(k)), path.clone());
                    let table = item
                        .cast::<PyDict>()
                        .map_err(|_| PyException::new_err("not a dict"))?;
                    document.leaves(table, "", &path, &mut up)?;
                }
                up.leave();
            }
        }
        Ok(document)
    }

    /// The key path of a 1-based line (the document itself for line 0 or
    /// past the end: a missing key).
    pub fn key_path_at_line(&self, line: usize) -> String {
        match line.checked_sub(1).and_then(|i| self.paths.get(i)) {
            Some(path) => path.clone(),
            None => "(top level)".into(),
        }
    }
}
