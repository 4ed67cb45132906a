//! `.usda` reader for the subset grooms use: layer metadata, prims with
//! specifiers and types, typed attributes with default values, time samples
//! and metadata. Relationships, connections, dictionaries, list edits and
//! variant sets are parsed and skipped. Every error names line:column.

use super::{
    element_kind, Arc, ArcKind, ArcTarget, ElementKind, LayerOffset, Prim, Specifier, Stage,
    UsdAttribute, Value,
};
use crate::{ImportError, Place};
use std::path::Path;

/// Deepest prim or bracket nesting accepted, so hostile files cannot
/// exhaust the stack.
const MAX_DEPTH: usize = 256;

pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<Stage, ImportError> {
    let mut parser = Parser {
        lexer: Lexer::new(path, bytes),
        peeked: None,
        stage: Stage::default(),
        attribute_index: std::collections::HashMap::new(),
    };
    parser.lexer.skip_header()?;
    parser.layer()?;
    Ok(parser.stage)
}

#[derive(Debug, Clone, PartialEq)]
enum Token<'a> {
    Punct(u8),
    Number(&'a str),
    Text(String),
    Ident(&'a str),
    /// `<...>`
    Path(&'a str),
    /// `@...@`
    Asset(String),
    Eof,
}

impl Token<'_> {
    fn describe(&self) -> String {
        match self {
            Token::Punct(c) => format!("'{}'", *c as char),
            Token::Number(n) => format!("number {n}"),
            Token::Text(t) => format!("string \"{}\"", t.chars().take(40).collect::<String>()),
            Token::Ident(i) => format!("'{i}'"),
            Token::Path(p) => format!("path <{p}>"),
            Token::Asset(a) => format!("asset @{a}@"),
            Token::Eof => "end of file".into(),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Position {
    line: usize,
    column: usize,
}

impl Position {
    fn place(self) -> Place {
        Place::Line {
            line: self.line,
            column: self.column,
        }
    }
}

struct Lexer<'a> {
    file: &'a Path,
    text: &'a [u8],
    offset: usize,
    line: usize,
    line_start: usize,
}

impl<'a> Lexer<'a> {
    fn new(file: &'a Path, text: &'a [u8]) -> Lexer<'a> {
        Lexer {
            file,
            text,
            offset: 0,
            line: 1,
            line_start: 0,
        }
    }

    fn position(&self) -> Position {
        Position {
            line: self.line,
            column: self.offset - self.line_start + 1,
        }
    }

    fn error_at(&self, at: Position, message: impl Into<String>) -> ImportError {
        ImportError::malformed(self.file, at.place(), message)
    }

    /// Checks and skips the `#usda 1.0` line.
    fn skip_header(&mut self) -> Result<(), ImportError> {
        let end = self
            .text
            .iter()
            .position(|&b| b == b'\n')
            .unwrap_or(self.text.len());
        let header = String::from_utf8_lossy(self.text.get(..end).unwrap_or_default());
        let version = header.trim_start_matches("#usda").trim();
        if !version.starts_with("1.") {
            return Err(self.error_at(
                self.position(),
                format!("unsupported usda version '{version}' (expected 1.x)"),
            ));
        }
        self.offset = end;
        Ok(())
    }

    fn peek_byte(&self, ahead: usize) -> Option<u8> {
        self.text.get(self.offset + ahead).copied()
    }

    fn bump(&mut self) -> Option<u8> {
        let byte = self.peek_byte(0)?;
        self.offset += 1;
        if byte == b'\n' {
            self.line += 1;
            self.line_start = self.offset;
        }
        Some(byte)
    }

    fn skip_space(&mut self) {
        while let Some(byte) = self.peek_byte(0) {
            match byte {
                b' ' | b'\t' | b'\r' | b'\n' => {
                    self.bump();
                }
                b'#' => {
                    while self.peek_byte(0).is_some_and(|b| b != b'\n') {
                        self.bump();
                    }
                }
                b'/' if self.peek_byte(1) == Some(b'/') => {
                    while self.peek_byte(0).is_some_and(|b| b != b'\n') {
                        self.bump();
                    }
                }
                b'/' if self.peek_byte(1) == Some(b'*') => {
                    self.bump();
                    self.bump();
                    while self.peek_byte(0).is_some()
                        && !(self.peek_byte(0) == Some(b'*') && self.peek_byte(1) == Some(b'/'))
                    {
                        self.bump();
                    }
                    self.bump();
                    self.bump();
                }
                _ => return,
            }
        }
    }

    fn slice(&self, start: usize) -> Result<&'a str, ImportError> {
        let bytes = self.text.get(start..self.offset).unwrap_or_default();
        std::str::from_utf8(bytes).map_err(|_| self.error_at(self.position(), "invalid UTF-8"))
    }

    fn next(&mut self) -> Result<(Token<'a>, Position), ImportError> {
        self.skip_space();
        let at = self.position();
        let Some(byte) = self.peek_byte(0) else {
            return Ok((Token::Eof, at));
        };
        let start = self.offset;
        let token = match byte {
            b'(' | b')' | b'[' | b']' | b'{' | b'}' | b'=' | b',' | b':' | b';' => {
                self.bump();
                Token::Punct(byte)
            }
            b'"' | b'\'' => Token::Text(self.string(byte, at)?),
            b'<' => {
                self.bump();
                while self.peek_byte(0).is_some_and(|b| b != b'>' && b != b'\n') {
                    self.bump();
                }
                if self.peek_byte(0) != Some(b'>') {
                    return Err(self.error_at(at, "path without closing '>'"));
                }
                let path = self.slice(start + 1)?;
                self.bump();
                Token::Path(path)
            }
            b'@' => {
                let triple = self.text.get(self.offset..self.offset + 3) == Some(b"@@@");
                let delimiter: &[u8] = if triple { b"@@@" } else { b"@" };
                for _ in 0..delimiter.len() {
                    self.bump();
                }
                let content = self.offset;
                loop {
                    if self.text.get(self.offset..self.offset + delimiter.len()) == Some(delimiter)
                    {
                        break;
                    }
                    if self.bump().is_none() {
                        return Err(self.error_at(at, "asset path without closing '@'"));
                    }
                }
                let text = self.slice(content)?.to_string();
                for _ in 0..delimiter.len() {
                    self.bump();
                }
                Token::Asset(text)
            }
            b'0'..=b'9' | b'-' | b'+' | b'.' => {
                self.bump();
                while self
                    .peek_byte(0)
                    .is_some_and(|b| b.is_ascii_alphanumeric() || matches!(b, b'.' | b'-' | b'+'))
                {
                    self.bump();
                }
                Token::Number(self.slice(start)?)
            }
            b if b.is_ascii_alphabetic() || b == b'_' => {
                while self
                    .peek_byte(0)
                    .is_some_and(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b':' | b'.'))
                {
                    self.bump();
                }
                Token::Ident(self.slice(start)?)
            }
            other => {
                return Err(self.error_at(
                    at,
                    format!(
                        "unexpected character '{}'",
                        (other as char).escape_default()
                    ),
                ))
            }
        };
        Ok((token, at))
    }

    fn string(&mut self, quote: u8, at: Position) -> Result<String, ImportError> {
        let triple = self.peek_byte(1) == Some(quote) && self.peek_byte(2) == Some(quote);
        let width = if triple { 3 } else { 1 };
        for _ in 0..width {
            self.bump();
        }
        let mut out = Vec::new();
        loop {
            let Some(byte) = self.bump() else {
                return Err(self.error_at(at, "string without closing quote"));
            };
            if byte == quote
                && (!triple
                    || (self.peek_byte(0) == Some(quote) && self.peek_byte(1) == Some(quote)))
            {
                if triple {
                    self.bump();
                    self.bump();
                }
                break;
            }
            if byte == b'\n' && !triple {
                return Err(self.error_at(at, "string without closing quote on its line"));
            }
            if byte == b'\\' {
                let Some(escaped) = self.bump() else {
                    return Err(self.error_at(at, "string without closing quote"));
                };
                out.push(match escaped {
                    b'n' => b'\n',
                    b't' => b'\t',
                    b'r' => b'\r',
                    other => other,
                });
            } else {
                out.push(byte);
            }
        }
        String::from_utf8(out).map_err(|_| self.error_at(at, "string is not UTF-8"))
    }
}

struct Parser<'a> {
    lexer: Lexer<'a>,
    peeked: Option<(Token<'a>, Position)>,
    stage: Stage,
    /// (prim, attribute name) -> index in the prim's attributes: a prim of
    /// 100,000 primvars is read in linear time, not by a search per line.
    attribute_index: std::collections::HashMap<(usize, String), usize>,
}

impl<'a> Parser<'a> {
    fn peek(&mut self) -> Result<&Token<'a>, ImportError> {
        if self.peeked.is_none() {
            self.peeked = Some(self.lexer.next()?);
        }
        match &self.peeked {
            Some((token, _)) => Ok(token),
            None => Err(self
                .lexer
                .error_at(self.lexer.position(), "internal: no token")),
        }
    }

    fn next(&mut self) -> Result<(Token<'a>, Position), ImportError> {
        match self.peeked.take() {
            Some(token) => Ok(token),
            None => self.lexer.next(),
        }
    }

    fn error(&self, at: Position, message: impl Into<String>) -> ImportError {
        self.lexer.error_at(at, message)
    }

    fn expect(&mut self, punct: u8) -> Result<Position, ImportError> {
        let (token, at) = self.next()?;
        if token != Token::Punct(punct) {
            return Err(self.error(
                at,
                format!("expected '{}', found {}", punct as char, token.describe()),
            ));
        }
        Ok(at)
    }

    fn eat(&mut self, punct: u8) -> Result<bool, ImportError> {
        if *self.peek()? == Token::Punct(punct) {
            self.next()?;
            return Ok(true);
        }
        Ok(false)
    }

    fn layer(&mut self) -> Result<(), ImportError> {
        if *self.peek()? == Token::Punct(b'(') {
            let entries = self.metadata()?;
            for (key, value, at) in entries {
                let number = |v: &Value| v.numbers(1).and_then(|n| n.first().copied());
                let bad = |what: &str| self.error(at, format!("{key} must be {what}"));
                match key.as_str() {
                    "metersPerUnit" => {
                        self.stage.meters_per_unit =
                            Some(number(&value).ok_or_else(|| bad("a number"))?)
                    }
                    "timeCodesPerSecond" => {
                        self.stage.time_codes_per_second =
                            Some(number(&value).ok_or_else(|| bad("a number"))?)
                    }
                    "framesPerSecond" => {
                        self.stage.frames_per_second =
                            Some(number(&value).ok_or_else(|| bad("a number"))?)
                    }
                    "upAxis" => {
                        let axis = value
                            .text()
                            .and_then(|t| t.first().cloned())
                            .ok_or_else(|| bad("a string"))?;
                        self.stage.up_axis = Some(axis);
                    }
                    "defaultPrim" => {
                        self.stage.default_prim = value.text().and_then(|t| t.first().cloned());
                    }
                    "doc" => self.stage.doc = value.text().and_then(|t| t.first().cloned()),
                    "subLayers" => {
                        if let Value::Arcs(targets) = value {
                            for target in targets {
                                if let Some(asset) = target.asset {
                                    self.stage
                                        .sublayers
                                        .push((asset, at.place(), target.offset));
                                }
                            }
                        }
                    }
                    _ => {}
                }
            }
        }
        loop {
            let (token, at) = self.next()?;
            match token {
                Token::Eof => return Ok(()),
                Token::Ident(specifier @ ("def" | "over" | "class")) => {
                    self.prim(specifier, None, false, 0, at)?;
                }
                other => {
                    return Err(self.error(
                        at,
                        format!(
                            "expected a prim (def, over, class), found {}",
                            other.describe()
                        ),
                    ))
                }
            }
        }
    }

    /// `( entries )`; returns `(key, value, position)` of `key = value` entries.
    fn metadata(&mut self) -> Result<Vec<(String, Value, Position)>, ImportError> {
        self.expect(b'(')?;
        let mut entries = Vec::new();
        loop {
            let (token, at) = self.next()?;
            match token {
                Token::Punct(b')') => return Ok(entries),
                Token::Punct(b';') => {}
                // A bare string is the doc.
                Token::Text(_) => {}
                Token::Ident(word) => {
                    let list_op = word;
                    let key = match word {
                        "prepend" | "append" | "add" | "delete" | "reorder" => {
                            let (key, at) = self.next()?;
                            match key {
                                Token::Ident(key) => key,
                                other => {
                                    return Err(self.error(
                                        at,
                                        format!(
                                            "expected a metadata name, found {}",
                                            other.describe()
                                        ),
                                    ))
                                }
                            }
                        }
                        key => key,
                    };
                    if self.eat(b'=')? {
                        let arcs = ArcKind::of_key(key).is_some() || key == "subLayers";
                        if arcs && !matches!(list_op, "delete" | "reorder") {
                            let value = self.arc_list()?;
                            entries.push((key.to_string(), value, at));
                        } else {
                            let value = self.generic_value(0)?;
                            entries.push((key.to_string(), value, at));
                        }
                    }
                }
                other => {
                    return Err(self.error(
                        at,
                        format!("expected metadata or ')', found {}", other.describe()),
                    ))
                }
            }
        }
    }

    /// A composition arc list: `None`, one item or `[item, ...]`, each item
    /// `@asset@`, `</prim>` or `@asset@</prim>`, with optional `( ... )`
    /// (layer offsets, skipped).
    fn arc_list(&mut self) -> Result<Value, ImportError> {
        if *self.peek()? == Token::Ident("None") {
            self.next()?;
            return Ok(Value::Arcs(Vec::new()));
        }
        let list = self.eat(b'[')?;
        let mut targets = Vec::new();
        loop {
            if list && self.eat(b']')? {
                break;
            }
            let mut target = ArcTarget {
                asset: None,
                prim_path: None,
                offset: LayerOffset::default(),
            };
            if let Token::Asset(asset) = self.peek()? {
                target.asset = Some(asset.clone());
                self.next()?;
            }
            if let Token::Path(path) = self.peek()? {
                target.prim_path = Some(path.to_string());
                self.next()?;
            }
            if target.asset.is_none() && target.prim_path.is_none() {
                let (token, at) = self.next()?;
                return Err(self.error(
                    at,
                    format!(
                        "expected an arc target (@asset@ or </path>), found {}",
                        token.describe()
                    ),
                ));
            }
            if *self.peek()? == Token::Punct(b'(') {
                target.offset = self.layer_offset()?;
            }
            targets.push(target);
            if !list {
                break;
            }
            if !self.eat(b',')? {
                self.expect(b']')?;
                break;
            }
        }
        Ok(Value::Arcs(targets))
    }

    /// An arc's or a sublayer's `(offset = N; scale = N)`; other entries
    /// are skipped.
    fn layer_offset(&mut self) -> Result<LayerOffset, ImportError> {
        self.expect(b'(')?;
        let mut offset = LayerOffset::default();
        loop {
            if self.eat(b')')? {
                break;
            }
            if self.eat(b';')? {
                continue;
            }
            let (token, at) = self.next()?;
            let key = match token {
                Token::Ident(key) => key,
                other => {
                    return Err(self.error(
                        at,
                        format!("expected a layer offset entry, found {}", other.describe()),
                    ))
                }
            };
            self.expect(b'=')?;
            let value = self.generic_value(0)?;
            let number = match value {
                Value::Numbers { data, .. } => data.first().copied(),
                _ => None,
            };
            let slot = match key {
                "offset" => &mut offset.offset,
                "scale" => &mut offset.scale,
                _ => continue,
            };
            *slot = number
                .filter(|n| n.is_finite())
                .ok_or_else(|| self.error(at, format!("layer {key} is not a finite number")))?;
        }
        Ok(offset)
    }

    /// Any value, interpreted only as far as a number or a string; lists,
    /// tuples and dictionaries are skipped.
    fn generic_value(&mut self, depth: usize) -> Result<Value, ImportError> {
        if depth > MAX_DEPTH {
            let at = self.lexer.position();
            return Err(self.error(at, "values nested too deeply"));
        }
        let (token, at) = self.next()?;
        Ok(match token {
            Token::Number(text) => {
                let number = parse_number(text, false)
                    .ok_or_else(|| self.error(at, format!("'{text}' is not a number")))?;
                Value::Numbers {
                    components: 1,
                    array: false,
                    data: vec![number],
                }
            }
            Token::Text(text) | Token::Asset(text) => Value::Text {
                array: false,
                data: vec![text],
            },
            Token::Ident("None") => Value::Blocked,
            Token::Ident(_) | Token::Path(_) => Value::Other,
            Token::Punct(open @ (b'[' | b'(' | b'{')) => {
                let close = match open {
                    b'[' => b']',
                    b'(' => b')',
                    _ => b'}',
                };
                self.skip_until(close, at, depth)?;
                Value::Other
            }
            other => {
                return Err(self.error(at, format!("expected a value, found {}", other.describe())))
            }
        })
    }

    /// Skips tokens up to the bracket closing one opened at `opened`.
    fn skip_until(&mut self, close: u8, opened: Position, depth: usize) -> Result<(), ImportError> {
        let mut stack = vec![close];
        while let Some(&expected) = stack.last() {
            if stack.len() + depth > MAX_DEPTH {
                return Err(self.error(opened, "brackets nested too deeply"));
            }
            let (token, at) = self.next()?;
            match token {
                Token::Eof => {
                    return Err(self.error(
                        opened,
                        format!("bracket never closed (expected '{}')", expected as char),
                    ))
                }
                Token::Punct(b'[') => stack.push(b']'),
                Token::Punct(b'(') => stack.push(b')'),
                Token::Punct(b'{') => stack.push(b'}'),
                Token::Punct(c @ (b']' | b')' | b'}')) => {
                    if c != expected {
                        return Err(self.error(
                            at,
                            format!("expected '{}', found '{}'", expected as char, c as char),
                        ));
                    }
                    stack.pop();
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn prim(
        &mut self,
        specifier: &str,
        parent: Option<usize>,
        in_variant: bool,
        depth: usize,
        at: Position,
    ) -> Result<(), ImportError> {
        if depth > MAX_DEPTH {
            return Err(self.error(at, "prims nested too deeply"));
        }
        let specifier = match specifier {
            "def" => Specifier::Def,
            "over" => Specifier::Over,
            _ => Specifier::Class,
        };
        let (mut token, mut token_at) = self.next()?;
        let mut type_name = String::new();
        if let Token::Ident(name) = token {
            type_name = name.to_string();
            (token, token_at) = self.next()?;
        }
        let Token::Text(name) = token else {
            return Err(self.error(
                token_at,
                format!(
                    "expected the prim's name in quotes, found {}",
                    token.describe()
                ),
            ));
        };
        if name.is_empty() || !name.chars().all(|c| c.is_alphanumeric() || c == '_') {
            return Err(self.error(token_at, format!("'{name}' is not a valid prim name")));
        }
        let path = match parent.and_then(|p| self.stage.prims.get(p)) {
            Some(parent) => format!("{}/{name}", parent.path),
            None => format!("/{name}"),
        };
        let mut arcs = Vec::new();
        if *self.peek()? == Token::Punct(b'(') {
            for (key, value, arc_at) in self.metadata()? {
                if let (Some(kind), Value::Arcs(targets)) = (ArcKind::of_key(&key), value) {
                    arcs.push(Arc {
                        kind,
                        targets,
                        place: arc_at.place(),
                    });
                }
            }
        }
        arcs.sort_by_key(|arc: &Arc| arc.kind.strength());
        self.expect(b'{')?;
        let index = self.stage.prims.len();
        self.stage.prims.push(Prim {
            path,
            parent,
            type_name,
            specifier,
            in_variant,
            attributes: Vec::new(),
            arcs,
            place: at.place(),
        });
        self.prim_body(index, in_variant, depth)
    }

    /// Statements up to the closing `}` of a prim (or variant) body.
    fn prim_body(
        &mut self,
        index: usize,
        in_variant: bool,
        depth: usize,
    ) -> Result<(), ImportError> {
        loop {
            let (token, at) = self.next()?;
            match token {
                Token::Punct(b'}') => return Ok(()),
                Token::Punct(b';') => {}
                Token::Ident(specifier @ ("def" | "over" | "class")) => {
                    self.prim(specifier, Some(index), in_variant, depth + 1, at)?;
                }
                Token::Ident("variantSet") => self.variant_set(index, depth, at)?,
                Token::Ident("reorder")
                    if matches!(self.peek()?, Token::Ident("nameChildren" | "properties")) =>
                {
                    self.next()?;
                    self.expect(b'=')?;
                    self.generic_value(0)?;
                }
                Token::Ident(first) => self.property(index, first, at)?,
                Token::Eof => return Err(self.error(at, "prim body never closed (missing '}')")),
                other => {
                    return Err(self.error(
                        at,
                        format!("expected a property or prim, found {}", other.describe()),
                    ))
                }
            }
        }
    }

    /// `variantSet "name" = { "variant" (meta) { body } ... }`: parsed so the
    /// file is checked, its prims marked as not on the stage.
    fn variant_set(&mut self, index: usize, depth: usize, at: Position) -> Result<(), ImportError> {
        if depth > MAX_DEPTH {
            return Err(self.error(at, "variants nested too deeply"));
        }
        let (name, name_at) = self.next()?;
        let Token::Text(name) = name else {
            return Err(self.error(
                name_at,
                format!("expected the variant set's name, found {}", name.describe()),
            ));
        };
        let owner = self.stage.prims.get(index).map(|p| p.path.clone());
        self.stage.notes.push(format!(
            "{}: variant set '{name}' not applied",
            owner.unwrap_or_default()
        ));
        self.expect(b'=')?;
        self.expect(b'{')?;
        loop {
            let (token, at) = self.next()?;
            match token {
                Token::Punct(b'}') => return Ok(()),
                Token::Text(_) => {
                    if *self.peek()? == Token::Punct(b'(') {
                        self.metadata()?;
                    }
                    self.expect(b'{')?;
                    self.prim_body(index, true, depth + 1)?;
                }
                other => {
                    return Err(self.error(
                        at,
                        format!("expected a variant name, found {}", other.describe()),
                    ))
                }
            }
        }
    }

    fn property(&mut self, prim: usize, first: &'a str, at: Position) -> Result<(), ImportError> {
        let mut word = first;
        let mut word_at = at;
        // List edits (`prepend rel ...`) and qualifiers come before the type.
        while matches!(
            word,
            "custom"
                | "uniform"
                | "varying"
                | "config"
                | "add"
                | "delete"
                | "prepend"
                | "append"
                | "reorder"
        ) {
            let (token, token_at) = self.next()?;
            let Token::Ident(next) = token else {
                return Err(self.error(
                    token_at,
                    format!("expected a type, found {}", token.describe()),
                ));
            };
            word = next;
            word_at = token_at;
        }
        if word == "rel" {
            let (name, name_at) = self.next()?;
            if !matches!(name, Token::Ident(_)) {
                return Err(self.error(
                    name_at,
                    format!("expected a relationship name, found {}", name.describe()),
                ));
            }
            if self.eat(b'=')? {
                self.generic_value(0)?;
            }
            if *self.peek()? == Token::Punct(b'(') {
                self.metadata()?;
            }
            return Ok(());
        }
        // Sdf's legacy type names read as the types usd-core maps them to.
        let type_name = legacy_type_alias(word).unwrap_or(word);
        let array = if self.eat(b'[')? {
            self.expect(b']')?;
            true
        } else {
            false
        };
        let (name_token, name_at) = self.next()?;
        let Token::Ident(full_name) = name_token else {
            return Err(self.error(
                name_at,
                format!(
                    "expected an attribute name after '{type_name}', found {}",
                    name_token.describe()
                ),
            ));
        };
        let (name, suffix) = match full_name.rsplit_once('.') {
            Some((name, suffix @ ("timeSamples" | "connect" | "spline" | "default"))) => {
                (name, suffix)
            }
            Some(_) => {
                return Err(self.error(name_at, format!("'{full_name}' is not an attribute name")))
            }
            None => (full_name, ""),
        };
        let kind = element_kind(type_name);
        if kind.is_none() && !matches!(type_name, "opaque" | "dictionary" | "pathExpression") {
            // Unknown types are skipped, but the name must still look like a type.
            if !type_name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_')
            {
                return Err(self.error(word_at, format!("'{type_name}' is not a type name")));
            }
        }
        let mut default = None;
        let mut samples = Vec::new();
        if self.eat(b'=')? {
            match suffix {
                "timeSamples" => samples = self.time_samples(kind, array)?,
                "spline" => return Err(self.error(name_at, "spline values are not supported")),
                "connect" => {
                    self.generic_value(0)?;
                }
                _ => default = Some(self.typed_value(kind, array)?),
            }
        }
        let mut interpolation = None;
        let mut element_size = None;
        if *self.peek()? == Token::Punct(b'(') {
            for (key, value, meta_at) in self.metadata()? {
                if key == "elementSize" {
                    let size = value.numbers(1).and_then(|n| n.first().copied());
                    element_size = Some(
                        size.ok_or_else(|| self.error(meta_at, "elementSize must be a number"))?,
                    );
                }
                if key == "interpolation" {
                    let text = value.text().and_then(|t| t.first().cloned());
                    interpolation =
                        Some(text.ok_or_else(|| {
                            self.error(meta_at, "interpolation must be a string")
                        })?);
                }
            }
        }
        let prim_index = prim;
        let Some(prim) = self.stage.prims.get_mut(prim) else {
            return Ok(());
        };
        // `name.timeSamples` and `name` (with metadata) are one attribute.
        let known = self
            .attribute_index
            .get(&(prim_index, name.to_string()))
            .copied();
        if let Some(existing) = known.and_then(|i| prim.attributes.get_mut(i)) {
            if default.is_some() {
                existing.default = default;
            }
            if !samples.is_empty() {
                existing.samples = samples;
            }
            if interpolation.is_some() {
                existing.interpolation = interpolation;
            }
            if element_size.is_some() {
                existing.element_size = element_size;
            }
            return Ok(());
        }
        self.attribute_index
            .insert((prim_index, name.to_string()), prim.attributes.len());
        prim.attributes.push(UsdAttribute {
            name: name.to_string(),
            type_name: if array {
                format!("{type_name}[]")
            } else {
                type_name.to_string()
            },
            default,
            samples,
            interpolation,
            element_size,
            place: at.place(),
        });
        Ok(())
    }

    fn time_samples(
        &mut self,
        kind: Option<ElementKind>,
        array: bool,
    ) -> Result<Vec<(f64, Value)>, ImportError> {
        self.expect(b'{')?;
        let mut samples = Vec::new();
        loop {
            let (token, at) = self.next()?;
            let code = match token {
                Token::Punct(b'}') => return Ok(samples),
                Token::Number(text) => parse_number(text, false)
                    .ok_or_else(|| self.error(at, format!("'{text}' is not a time code")))?,
                other => {
                    return Err(self.error(
                        at,
                        format!("expected a time code, found {}", other.describe()),
                    ))
                }
            };
            self.expect(b':')?;
            let value = self.typed_value(kind, array)?;
            samples.push((code, value));
            if !self.eat(b',')? && *self.peek()? != Token::Punct(b'}') {
                let (token, at) = self.next()?;
                return Err(self.error(
                    at,
                    format!("expected ',' or '}}', found {}", token.describe()),
                ));
            }
        }
    }

    fn typed_value(
        &mut self,
        kind: Option<ElementKind>,
        array: bool,
    ) -> Result<Value, ImportError> {
        let Some(kind) = kind else {
            self.generic_value(0)?;
            return Ok(Value::Other);
        };
        if let Token::Ident("None") = self.peek()? {
            self.next()?;
            return Ok(Value::Blocked);
        }
        if !array {
            return self.element_value(kind);
        }
        let open = self.expect(b'[')?;
        let mut numbers = Vec::new();
        let mut texts = Vec::new();
        loop {
            if self.eat(b']')? {
                break;
            }
            if *self.peek()? == Token::Eof {
                return Err(self.error(open, "array never closed (missing ']')"));
            }
            match kind {
                ElementKind::Numbers { components, single } => {
                    self.numbers_element(components, single, &mut numbers)?
                }
                ElementKind::Text => texts.push(self.text_element()?),
            }
            if !self.eat(b',')? && *self.peek()? != Token::Punct(b']') {
                let (token, at) = self.next()?;
                if token == Token::Eof {
                    return Err(self.error(open, "array never closed (missing ']')"));
                }
                return Err(self.error(
                    at,
                    format!("expected ',' or ']', found {}", token.describe()),
                ));
            }
        }
        Ok(match kind {
            ElementKind::Numbers { components, .. } => Value::Numbers {
                components,
                array: true,
                data: numbers,
            },
            ElementKind::Text => Value::Text {
                array: true,
                data: texts,
            },
        })
    }

    fn element_value(&mut self, kind: ElementKind) -> Result<Value, ImportError> {
        let array = false;
        Ok(match kind {
            ElementKind::Numbers { components, single } => {
                let mut data = Vec::with_capacity(components);
                self.numbers_element(components, single, &mut data)?;
                Value::Numbers {
                    components,
                    array,
                    data,
                }
            }
            ElementKind::Text => Value::Text {
                array,
                data: vec![self.text_element()?],
            },
        })
    }

    fn text_element(&mut self) -> Result<String, ImportError> {
        let (token, at) = self.next()?;
        match token {
            Token::Text(text) | Token::Asset(text) => Ok(text),
            Token::Ident(ident) => Ok(ident.to_string()),
            other => Err(self.error(at, format!("expected a string, found {}", other.describe()))),
        }
    }

    /// One element: a number, or a parenthesised tuple (nested for
    /// matrices) of exactly `components` numbers.
    fn numbers_element(
        &mut self,
        components: usize,
        single: bool,
        out: &mut Vec<f64>,
    ) -> Result<(), ImportError> {
        let (token, at) = self.next()?;
        if components == 1 {
            out.push(self.number(token, at, single)?);
            return Ok(());
        }
        if token != Token::Punct(b'(') {
            return Err(self.error(
                at,
                format!(
                    "expected a tuple of {components} numbers, found {}",
                    token.describe()
                ),
            ));
        }
        let start = out.len();
        let mut depth = 1usize;
        loop {
            let (token, token_at) = self.next()?;
            match token {
                Token::Punct(b'(') => {
                    depth += 1;
                    if depth > 4 {
                        return Err(self.error(token_at, "tuple nested too deeply"));
                    }
                }
                Token::Punct(b')') => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                Token::Punct(b',') => {}
                other => {
                    if out.len() - start >= components {
                        return Err(self.error(
                            token_at,
                            format!("tuple has more than {components} numbers"),
                        ));
                    }
                    let number = self.number(other, token_at, single)?;
                    out.push(number);
                }
            }
        }
        if out.len() - start != components {
            return Err(self.error(
                at,
                format!(
                    "tuple has {} numbers, expected {components}",
                    out.len() - start
                ),
            ));
        }
        Ok(())
    }

    fn number(&self, token: Token<'_>, at: Position, single: bool) -> Result<f64, ImportError> {
        let text = match token {
            Token::Number(text) => text,
            Token::Ident(word @ ("inf" | "nan" | "true" | "false")) => word,
            other => {
                return Err(self.error(at, format!("expected a number, found {}", other.describe())))
            }
        };
        parse_number(text, single)
            .ok_or_else(|| self.error(at, format!("'{text}' is not a number")))
    }
}

/// A number as USD writes it; `single` parses 32-bit floats as f32 first
/// so the value is the one a C++ reader would store.
fn parse_number(text: &str, single: bool) -> Option<f64> {
    match text {
        "true" => return Some(1.0),
        "false" => return Some(0.0),
        _ => {}
    }
    if single {
        text.parse::<f32>().ok().map(f64::from)
    } else {
        text.parse::<f64>().ok()
    }
}

/// The current name of one of Sdf's legacy value type names (`PointFloat`
/// is `point3f`), as usd-core still reads them; `None` for other names.
fn legacy_type_alias(name: &str) -> Option<&'static str> {
    Some(match name {
        "Vec2f" => "float2",
        "Vec3f" => "float3",
        "Vec4f" => "float4",
        "Vec2d" => "double2",
        "Vec3d" => "double3",
        "Vec4d" => "double4",
        "Vec2i" => "int2",
        "Vec3i" => "int3",
        "Vec4i" => "int4",
        "PointFloat" => "point3f",
        "Point" => "point3d",
        "NormalFloat" => "normal3f",
        "Normal" => "normal3d",
        "VectorFloat" => "vector3f",
        "Vector" => "vector3d",
        "ColorFloat" => "color3f",
        "Color" => "color3d",
        "Quatf" => "quatf",
        "Quatd" => "quatd",
        "Matrix4d" => "matrix4d",
        _ => return None,
    })
}
