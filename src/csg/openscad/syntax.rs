//! The syntax of OpenSCAD's flattened `.csg` files: the models OpenSCAD users
//! already have, read as CSG solids (seed 003).
//!
//! OpenSCAD 2021.01 writes a `.csg` file as a tree of built-in nodes with literal
//! arguments, every language feature evaluated away (the grammar, found by
//! experiment, is in `../shared/peers/openscad/CSG_FORMAT.md` §2):
//!
//! ```text
//! file   = { node } ;
//! node   = [ "%" ] [ "#" ] ident "(" [ arg { "," arg } ] ")" ( ";" | "{" { node } "}" ) ;
//! arg    = ident "=" value | value ;
//! value  = number | "true" | "false" | "undef" | string | "[" [ value { "," value } ] "]" ;
//! ```
//!
//! This module reads that grammar only; what the nodes mean (primitives,
//! transforms, booleans, what is out of scope) is decided by the model that is
//! built from the tree. Every node and argument keeps its byte span, so any
//! error — here or later — points at the file, line and column.
//!
//! Strings are not escaped by OpenSCAD (`text("a\"b")` is written `"a"b"`): a
//! string ends at the first `"` followed by `,`, `)` or `]`. Strings occur only
//! in nodes kage does not render.

use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

use crate::error::{Error, Result, SourceLocation};
use crate::limits::{Limit, LimitExceeded, Limits};

/// One node of a `.csg` file: `name(args);` or `name(args) { children }`.
#[derive(Debug, Clone, PartialEq)]
pub struct CsgNode {
    /// The node's name (`group`, `difference`, `multmatrix`, `cube`, ...).
    pub name: String,
    /// `%`: a background part, not part of the model (skipped by renderers).
    pub background: bool,
    /// `#`: highlighted in OpenSCAD's preview; part of the model as usual.
    pub highlight: bool,
    /// The arguments, in the order written.
    pub args: Vec<CsgArg>,
    /// The child nodes.
    pub children: Vec<CsgNode>,
    /// Bytes from the first modifier or the name to the closing `;` or `}`.
    pub span: Range<usize>,
}

/// One argument: `name = value`, or a bare value (`multmatrix`'s matrix).
#[derive(Debug, Clone, PartialEq)]
pub struct CsgArg {
    /// The name, if one was written.
    pub name: Option<String>,
    /// The value.
    pub value: CsgValue,
    /// Bytes of the whole argument.
    pub span: Range<usize>,
}

/// A literal value.
#[derive(Debug, Clone, PartialEq)]
pub enum CsgValue {
    /// A number (`inf` and `nan` included).
    Number(f64),
    /// `true` or `false`.
    Bool(bool),
    /// `undef`.
    Undef,
    /// A string, as written (OpenSCAD does not escape quotes).
    Text(String),
    /// `[a, b, ...]`, possibly nested.
    Vector(Vec<CsgValue>),
}

impl CsgNode {
    /// The argument called `name`, if written.
    #[must_use]
    pub fn arg(&self, name: &str) -> Option<&CsgArg> {
        self.args.iter().find(|a| a.name.as_deref() == Some(name))
    }
}

/// Parses the text of a `.csg` file (named `path` in messages) into its top-level
/// nodes. Errors carry the file, line and column of the offending characters.
///
/// # Errors
///
/// [`Error::CsgSyntax`] where the text leaves OpenSCAD's grammar, located
/// at the offending characters.
pub fn parse_csg(path: &Path, text: Arc<str>, limits: &Limits) -> Result<Vec<CsgNode>> {
    let max_depth = usize::try_from(limits.get(Limit::Nesting)).unwrap_or(usize::MAX);
    let mut p = Parser { text: &text, pos: 0, depth: 0, max_depth };
    let nodes = p.nodes(None);
    nodes.map_err(|(span, message)| Error::CsgSyntax {
        location: Box::new(SourceLocation::new(path, Arc::clone(&text), span)),
        message,
    })
}

/// A syntax error: where, and what was expected.
type Failure = (Range<usize>, String);

/// A recursive-descent reader over the file's bytes.
struct Parser<'t> {
    text: &'t str,
    pos: usize,
    /// `{` blocks and `[` vectors open around the reader.
    depth: usize,
    /// The [`Limit::Nesting`] of `depth`: OpenSCAD exports nest a few tens
    /// of levels; 100,000 would overflow the stack of the reader and of
    /// everything that walks the tree it builds.
    max_depth: usize,
}

impl<'t> Parser<'t> {
    /// Nodes up to the end of the file (`open` = `None`) or up to the `}` that
    /// closes the `{` at byte `open`.
    fn nodes(&mut self, open: Option<usize>) -> std::result::Result<Vec<CsgNode>, Failure> {
        let mut nodes = Vec::new();
        loop {
            self.skip_space();
            match (self.peek(), open) {
                (None, None) => return Ok(nodes),
                (None, Some(at)) => {
                    return Err((at..at + 1, "this `{` is never closed (the file ends first)".into()));
                }
                (Some(b'}'), Some(_)) => {
                    self.pos += 1;
                    return Ok(nodes);
                }
                (Some(b'}'), None) => return Err(self.here("`}` without a matching `{`")),
                _ => nodes.push(self.node()?),
            }
        }
    }

    fn node(&mut self) -> std::result::Result<CsgNode, Failure> {
        let start = self.pos;
        let (mut background, mut highlight) = (false, false);
        while let Some(c @ (b'%' | b'#')) = self.peek() {
            (background, highlight) = (background || c == b'%', highlight || c == b'#');
            self.pos += 1;
            self.skip_space();
        }
        let Some(name) = self.ident() else { return Err(self.here("expected a node name (like `cube` or `group`)")) };
        self.expect(b'(', &format!("expected `(` after `{name}`"))?;
        let args = self.args()?;
        self.skip_space();
        let children = match self.peek() {
            Some(b';') => {
                self.pos += 1;
                Vec::new()
            }
            Some(b'{') => {
                self.pos += 1;
                self.nested(|p| p.nodes(Some(p.pos - 1)))?
            }
            _ => return Err(self.here(&format!("expected `;` or `{{` after `{name}(...)`"))),
        };
        Ok(CsgNode { name: name.to_string(), background, highlight, args, children, span: start..self.pos })
    }

    /// Arguments after `(`, through the closing `)`.
    fn args(&mut self) -> std::result::Result<Vec<CsgArg>, Failure> {
        let mut args = Vec::new();
        self.skip_space();
        if self.peek() == Some(b')') {
            self.pos += 1;
            return Ok(args);
        }
        loop {
            self.skip_space();
            let start = self.pos;
            let name = self.named();
            let value = self.value()?;
            args.push(CsgArg { name, value, span: start..self.pos });
            self.skip_space();
            match self.peek() {
                Some(b',') => self.pos += 1,
                Some(b')') => {
                    self.pos += 1;
                    return Ok(args);
                }
                _ => return Err(self.here("expected `,` or `)` after an argument")),
            }
        }
    }

    /// `name =` if that is what comes next (consumed), else nothing (and nothing read).
    fn named(&mut self) -> Option<String> {
        let start = self.pos;
        if let Some(name) = self.ident() {
            self.skip_space();
            if self.peek() == Some(b'=') {
                self.pos += 1;
                self.skip_space();
                return Some(name.to_string());
            }
        }
        self.pos = start;
        None
    }

    fn value(&mut self) -> std::result::Result<CsgValue, Failure> {
        self.skip_space();
        match self.peek() {
            Some(b'[') => self.nested(Self::vector),
            Some(b'"') => Ok(self.string()),
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.pos;
                let word = self.ident().unwrap_or_default();
                match word {
                    "true" => Ok(CsgValue::Bool(true)),
                    "false" => Ok(CsgValue::Bool(false)),
                    "undef" => Ok(CsgValue::Undef),
                    "inf" => Ok(CsgValue::Number(f64::INFINITY)),
                    "nan" => Ok(CsgValue::Number(f64::NAN)),
                    _ => Err((start..self.pos, format!("expected a value, found `{word}`"))),
                }
            }
            Some(b'-' | b'+' | b'.' | b'0'..=b'9') => self.number(),
            _ => Err(self.here("expected a value (a number, `[`, `true`, `false`, `undef` or a string)")),
        }
    }

    /// Reads with `read` one level deeper, refusing past `max_depth`.
    fn nested<T>(
        &mut self,
        read: impl FnOnce(&mut Self) -> std::result::Result<T, Failure>,
    ) -> std::result::Result<T, Failure> {
        if self.depth >= self.max_depth {
            let at = self.pos.saturating_sub(1);
            let refused = LimitExceeded {
                limit: Limit::Nesting,
                asked: self.depth as u64 + 1,
                allowed: self.max_depth as u64,
                what: "the nesting of blocks and vectors".into(),
            };
            return Err((at..at + 1, refused.to_string()));
        }
        self.depth += 1;
        let read = read(self);
        self.depth -= 1;
        read
    }

    fn vector(&mut self) -> std::result::Result<CsgValue, Failure> {
        let open = self.pos;
        self.pos += 1;
        let mut items = Vec::new();
        self.skip_space();
        if self.peek() == Some(b']') {
            self.pos += 1;
            return Ok(CsgValue::Vector(items));
        }
        loop {
            items.push(self.value()?);
            self.skip_space();
            match self.peek() {
                Some(b',') => self.pos += 1,
                Some(b']') => {
                    self.pos += 1;
                    return Ok(CsgValue::Vector(items));
                }
                None => return Err((open..open + 1, "this `[` is never closed".into())),
                _ => return Err(self.here("expected `,` or `]` in a vector")),
            }
        }
    }

    /// A number as OpenSCAD writes them: `[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?`,
    /// or `-inf`.
    fn number(&mut self) -> std::result::Result<CsgValue, Failure> {
        let start = self.pos;
        let bytes = self.text.as_bytes();
        let mut end = start;
        while end < bytes.len() && (bytes[end].is_ascii_alphanumeric() || b"+-.".contains(&bytes[end])) {
            // A sign only leads the number or follows its exponent's `e`.
            if b"+-".contains(&bytes[end]) && end > start && !b"eE".contains(&bytes[end - 1]) {
                break;
            }
            end += 1;
        }
        self.pos = end;
        let word = &self.text[start..end];
        let value = match word {
            "-inf" => Some(f64::NEG_INFINITY),
            "+inf" => Some(f64::INFINITY),
            _ if word.bytes().all(|b| b.is_ascii_digit() || b"+-.eE".contains(&b)) => word.parse().ok(),
            _ => None,
        };
        value.map(CsgValue::Number).ok_or_else(|| (start..end, format!("`{word}` is not a number")))
    }

    /// A string from its opening quote: it ends at the first `"` followed (after
    /// spaces) by `,`, `)` or `]`, as OpenSCAD does not escape quotes inside.
    fn string(&mut self) -> CsgValue {
        let body = self.pos + 1;
        let bytes = self.text.as_bytes();
        let mut end = body;
        while end < bytes.len() {
            if bytes[end] == b'"' {
                let after = self.text[end + 1..].trim_start_matches([' ', '\t']);
                if after.is_empty() || after.starts_with([',', ')', ']', '\n', '\r']) {
                    break;
                }
            }
            end += 1;
        }
        self.pos = (end + 1).min(bytes.len());
        CsgValue::Text(self.text[body..end.min(bytes.len())].to_string())
    }

    /// An identifier (`$fn` included), if one starts here.
    fn ident(&mut self) -> Option<&'t str> {
        let bytes = self.text.as_bytes();
        let start = self.pos;
        let first = *bytes.get(start)?;
        if !(first.is_ascii_alphabetic() || first == b'_' || first == b'$') {
            return None;
        }
        let len = bytes[start..].iter().take_while(|b| b.is_ascii_alphanumeric() || **b == b'_' || **b == b'$').count();
        self.pos += len;
        Some(&self.text[start..start + len])
    }

    fn expect(&mut self, c: u8, message: &str) -> std::result::Result<(), Failure> {
        self.skip_space();
        if self.peek() == Some(c) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.here(message))
        }
    }

    fn skip_space(&mut self) {
        let rest = &self.text.as_bytes()[self.pos..];
        self.pos += rest.iter().take_while(|b| b.is_ascii_whitespace()).count();
    }

    fn peek(&self) -> Option<u8> {
        self.text.as_bytes().get(self.pos).copied()
    }

    /// A failure at the current character (or the end of the file).
    fn here(&self, message: &str) -> Failure {
        let end = self.text[self.pos..].chars().next().map_or(self.pos, |c| self.pos + c.len_utf8());
        let found = match self.text[self.pos..].chars().next() {
            Some(c) => format!(", found `{c}`"),
            None => ", found the end of the file".to_string(),
        };
        (self.pos..end, format!("{message}{found}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<CsgNode>> {
        parse_csg(Path::new("t.csg"), Arc::from(text), &Limits::default())
    }

    /// The (line, column) and message of the error `text` gives.
    fn error(text: &str) -> (usize, usize, String) {
        match parse(text) {
            Err(Error::CsgSyntax { location, message }) => (location.line, location.column, message),
            other => panic!("expected a syntax error, got {other:?}"),
        }
    }

    #[test]
    fn reads_nodes_arguments_modifiers_and_nesting() {
        let text = "group() {\n\tdifference() {\n\t\tsphere($fn = 0, $fa = 12, $fs = 2, r = 25);\n%#\t\tmultmatrix([[1, 0, 0, 0], [0, 0, -1, 1e-7], [0, 1, 0, -1.23457e+6], [0, 0, 0, 1]]) {\n\t\t\tcube(size = [1, 2, 3], center = true);\n\t\t}\n\t\ttext(text = \"a\"b\", font = \"\");\n\t}\n}\n";
        let nodes = parse(text).unwrap();
        assert_eq!(nodes.len(), 1);
        let diff = &nodes[0].children[0];
        assert_eq!(diff.name, "difference");
        let [sphere, matrix, label] = &diff.children[..] else { panic!("three children: {diff:?}") };
        assert_eq!(sphere.arg("r").map(|a| &a.value), Some(&CsgValue::Number(25.0)));
        assert_eq!(sphere.arg("$fa").map(|a| &a.value), Some(&CsgValue::Number(12.0)));
        assert!(matrix.background && matrix.highlight && !sphere.background);
        let CsgValue::Vector(rows) = &matrix.args[0].value else { panic!("a matrix") };
        assert_eq!(rows[1], CsgValue::Vector([0.0, 0.0, -1.0, 1e-7].map(CsgValue::Number).to_vec()));
        assert_eq!(rows[2], CsgValue::Vector([0.0, 1.0, 0.0, -1.23457e6].map(CsgValue::Number).to_vec()));
        assert_eq!(matrix.args[0].name, None);
        assert_eq!(matrix.children[0].arg("center").map(|a| &a.value), Some(&CsgValue::Bool(true)));
        assert_eq!(label.arg("text").map(|a| &a.value), Some(&CsgValue::Text("a\"b".into())));
        assert_eq!(label.arg("font").map(|a| &a.value), Some(&CsgValue::Text(String::new())));
        assert_eq!(&text[sphere.span.clone()], "sphere($fn = 0, $fa = 12, $fs = 2, r = 25);");
    }

    #[test]
    fn empty_files_and_empty_operators_parse() {
        assert!(parse("\n").unwrap().is_empty());
        let nodes = parse("union();\ngroup() {\n}\npolygon(points = [], paths = undef, convexity = 1);\n").unwrap();
        assert_eq!(nodes.len(), 3);
        assert_eq!(nodes[2].arg("paths").map(|a| &a.value), Some(&CsgValue::Undef));
    }

    #[test]
    fn malformed_files_fail_at_the_right_line_and_column() {
        // Truncated: the `{` of line 2 never closes.
        let (line, column, message) = error("group() {\n\tunion() {\n\t\tcube(size = [1, 1, 1], center = false);\n");
        assert_eq!((line, column), (2, 10), "{message}");
        assert!(message.contains("never closed"), "{message}");
        // A bad number.
        let (line, column, message) = error("group() {\n\tsphere(r = 1.2.3);\n}\n");
        assert_eq!((line, column), (2, 13), "{message}");
        assert!(message.contains("`1.2.3` is not a number"), "{message}");
        // One `}` too many.
        let (line, column, message) = error("cube(size = [1, 1, 1], center = false);\n}\n");
        assert_eq!((line, column), (2, 1), "{message}");
        // A missing `;`.
        let (line, column, message) = error("group() {\n\tcube(size = [1, 1, 1])\n\tsphere(r = 1);\n}\n");
        assert_eq!((line, column), (3, 2), "{message}");
        assert!(message.contains("expected `;` or `{`"), "{message}");
        // An unclosed vector, and a word that is not a value.
        assert_eq!(error("cube(size = [1, 1, 1);").0, 1);
        let (line, column, message) = error("cube(size = [1, 1, 1], center = maybe);");
        assert_eq!((line, column), (1, 33), "{message}");
        // Not a node at all.
        assert_eq!(error("group() {\n\t= cube();\n}").0, 2);
    }
}
