//! Where a value sits in a RON source: a small parser that keeps only the structure (struct fields,
//! tuple and list items) and the line and column where each value starts, so that a semantic error
//! found after deserialization can point at the offending value.
//!
//! It runs only on sources that RON has already accepted, and never fails: on anything it does not
//! understand it stops and answers with the deepest position it found.

/// A line and column in a source, both counted from 1, the column in characters (as RON counts them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Position {
    /// Line, from 1.
    pub line: usize,
    /// Column in characters, from 1.
    pub column: usize,
}

/// One step of a path from the root value to the value in question.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Seg {
    /// A named field of a struct (looks through `Some(..)` and newtype variants on the way).
    Field(&'static str),
    /// The item at this index of a tuple or list.
    Index(usize),
    /// Into the single item of `Name(..)` / `Some(..)` / `(..)`; nothing if the value is not one.
    Inner,
}

#[derive(Debug)]
enum Kind {
    /// Fields: name, where the name starts, the value.
    Struct(Vec<(String, Position, Node)>),
    Tuple(Vec<Node>),
    List(Vec<Node>),
    Atom,
}

#[derive(Debug)]
struct Node {
    pos: Position,
    /// Just after the value's last character.
    end: Position,
    kind: Kind,
}

/// The structure of a source, for [`Tree::position`].
#[derive(Debug)]
pub(crate) struct Tree {
    root: Option<Node>,
}

/// Deepest nesting followed; RON itself refuses deeper sources.
const MAX_DEPTH: usize = 256;

/// Most values kept in a tree (about 30 MiB): list items beyond them are read but not kept, so a huge
/// list costs no memory here, and an error in one points at the list. Struct fields and tuple items
/// are always kept up to [`ALWAYS_KEPT`] per struct or tuple, so that the way to a value after a huge
/// list is still found.
const MAX_NODES: usize = 1 << 18;

/// Fields of a struct, or items of a tuple, kept past [`MAX_NODES`] (schemas have fewer).
const ALWAYS_KEPT: usize = 16;

impl Tree {
    /// Parses as much of `src` as it can.
    pub(crate) fn parse(src: &str) -> Self {
        let mut p = Parser { src, i: 0, line: 1, column: 1, nodes: 0 };
        p.skip_ws();
        while p.peek() == Some('#') {
            p.skip_attribute();
            p.skip_ws();
        }
        Tree { root: p.value(0) }
    }

    /// The fields (name and where the name starts) of the struct that ends just before `end`, if any:
    /// RON reports a missing field at the end of its struct.
    pub(crate) fn struct_ending_at(&self, end: Position) -> Option<Vec<(String, Position)>> {
        fn walk(n: &Node, end: Position) -> Option<&Node> {
            // RON reports the position of the closing `)` or just after it.
            let near = n.end == end || (n.end.line == end.line && n.end.column == end.column + 1);
            if near && matches!(n.kind, Kind::Struct(_)) {
                return Some(n);
            }
            match &n.kind {
                Kind::Struct(f) => f.iter().find_map(|(_, _, v)| walk(v, end)),
                Kind::Tuple(items) | Kind::List(items) => items.iter().find_map(|v| walk(v, end)),
                Kind::Atom => None,
            }
        }
        let node = walk(self.root.as_ref()?, end)?;
        match &node.kind {
            Kind::Struct(f) => Some(f.iter().map(|(n, p, _)| (n.clone(), *p)).collect()),
            _ => None,
        }
    }

    /// Where the value at `path` starts, or the deepest value on the way when the path leads to a
    /// value the source does not spell out (a default).
    pub(crate) fn position(&self, path: &[Seg]) -> Position {
        let Some(mut node) = self.root.as_ref() else {
            return Position { line: 1, column: 1 };
        };
        for seg in path {
            match step(node, *seg) {
                Some(next) => node = next,
                None => break,
            }
        }
        node.pos
    }
}

fn step(mut node: &Node, seg: Seg) -> Option<&Node> {
    match seg {
        Seg::Field(name) => loop {
            match &node.kind {
                Kind::Struct(fields) => {
                    return fields
                        .iter()
                        .find(|(n, _, _)| n == name || n.strip_prefix("r#") == Some(name))
                        .map(|(_, _, v)| v);
                }
                Kind::Tuple(items) if items.len() == 1 => node = &items[0],
                _ => return None,
            }
        },
        Seg::Index(i) => match &node.kind {
            Kind::Tuple(items) | Kind::List(items) => items.get(i),
            _ => None,
        },
        Seg::Inner => match &node.kind {
            Kind::Tuple(items) if items.len() == 1 => items.first(),
            _ => Some(node),
        },
    }
}

struct Parser<'a> {
    src: &'a str,
    /// Byte offset of the next character.
    i: usize,
    line: usize,
    column: usize,
    /// Values kept so far (see [`MAX_NODES`]).
    nodes: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<char> {
        self.src[self.i..].chars().next()
    }

    fn peek_at(&self, k: usize) -> Option<char> {
        self.src[self.i..].chars().nth(k)
    }

    /// Whether another value, the `index`th of its struct, tuple (`short`) or list, may be kept;
    /// counts it.
    fn keep(&mut self, index: usize, short: bool) -> bool {
        self.nodes += 1;
        self.nodes <= MAX_NODES || (short && index < ALWAYS_KEPT)
    }

    fn bump(&mut self) -> Option<char> {
        let c = self.peek()?;
        self.i += c.len_utf8();
        if c == '\n' {
            self.line += 1;
            self.column = 1;
        } else {
            self.column += 1;
        }
        Some(c)
    }

    fn pos(&self) -> Position {
        Position { line: self.line, column: self.column }
    }

    fn skip_ws(&mut self) {
        loop {
            match (self.peek(), self.peek_at(1)) {
                (Some(c), _) if c.is_whitespace() => {
                    self.bump();
                }
                (Some('/'), Some('/')) => {
                    while let Some(c) = self.bump() {
                        if c == '\n' {
                            break;
                        }
                    }
                }
                (Some('/'), Some('*')) => {
                    self.bump();
                    self.bump();
                    let mut depth = 1usize;
                    while depth > 0 {
                        match (self.peek(), self.peek_at(1)) {
                            (None, _) => return,
                            (Some('*'), Some('/')) => {
                                self.bump();
                                self.bump();
                                depth -= 1;
                            }
                            (Some('/'), Some('*')) => {
                                self.bump();
                                self.bump();
                                depth += 1;
                            }
                            _ => {
                                self.bump();
                            }
                        }
                    }
                }
                _ => return,
            }
        }
    }

    fn skip_attribute(&mut self) {
        // `#![enable(...)]`: skip to the matching `]`.
        let mut depth = 0usize;
        while let Some(c) = self.bump() {
            match c {
                '[' => depth += 1,
                ']' => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 {
                        return;
                    }
                }
                _ => {}
            }
        }
    }

    fn is_ident_start(c: char) -> bool {
        c == '_' || c.is_alphabetic()
    }

    fn is_ident_char(c: char) -> bool {
        c == '_' || c.is_alphanumeric()
    }

    /// An identifier (raw or not), if one starts here. Raw identifiers may also hold `.`, `+`, `-`.
    fn ident(&mut self) -> Option<String> {
        let start = self.i;
        let raw = self.peek() == Some('r') && self.peek_at(1) == Some('#');
        if raw {
            self.bump();
            self.bump();
        } else if !self.peek().is_some_and(Self::is_ident_start) {
            return None;
        }
        while self.peek().is_some_and(|c| Self::is_ident_char(c) || (raw && matches!(c, '.' | '+' | '-'))) {
            self.bump();
        }
        Some(self.src[start..self.i].to_owned())
    }

    fn string(&mut self) {
        // At the opening quote.
        self.bump();
        while let Some(c) = self.bump() {
            match c {
                '\\' => {
                    self.bump();
                }
                '"' => return,
                _ => {}
            }
        }
    }

    fn raw_string(&mut self) {
        // At `r`, followed by `#`* and `"`.
        self.bump();
        let mut hashes = 0usize;
        while self.peek() == Some('#') {
            self.bump();
            hashes += 1;
        }
        self.bump(); // the quote
        while let Some(c) = self.bump() {
            if c == '"' {
                let mut n = 0usize;
                while n < hashes && self.peek() == Some('#') {
                    self.bump();
                    n += 1;
                }
                if n == hashes {
                    return;
                }
            }
        }
    }

    fn char_literal(&mut self) {
        self.bump();
        while let Some(c) = self.bump() {
            match c {
                '\\' => {
                    self.bump();
                }
                '\'' => return,
                _ => {}
            }
        }
    }

    fn is_raw_string_start(&self) -> bool {
        let mut k = 1;
        while self.peek_at(k) == Some('#') {
            k += 1;
        }
        self.peek_at(k) == Some('"') && (k > 1 || self.peek_at(1) == Some('"'))
    }

    fn value(&mut self, depth: usize) -> Option<Node> {
        if depth > MAX_DEPTH {
            return None;
        }
        self.skip_ws();
        let pos = self.pos();
        let c = self.peek()?;
        match c {
            '(' => {
                let kind = self.parens(depth)?;
                Some(Node { pos, end: self.pos(), kind })
            }
            '[' => {
                self.bump();
                let items = self.items(']', depth)?;
                Some(Node { pos, end: self.pos(), kind: Kind::List(items) })
            }
            '{' => {
                self.bump();
                // A map: keys and values, kept only to be skipped.
                loop {
                    self.skip_ws();
                    if self.peek() == Some('}') {
                        self.bump();
                        break;
                    }
                    self.value(depth + 1)?;
                    self.skip_ws();
                    if self.bump()? != ':' {
                        return None;
                    }
                    self.value(depth + 1)?;
                    self.skip_ws();
                    match self.bump()? {
                        ',' => {}
                        '}' => break,
                        _ => return None,
                    }
                }
                Some(Node { pos, end: self.pos(), kind: Kind::Atom })
            }
            '"' => {
                self.string();
                Some(Node { pos, end: self.pos(), kind: Kind::Atom })
            }
            '\'' => {
                self.char_literal();
                Some(Node { pos, end: self.pos(), kind: Kind::Atom })
            }
            'r' if self.is_raw_string_start() => {
                self.raw_string();
                Some(Node { pos, end: self.pos(), kind: Kind::Atom })
            }
            'b' if self.peek_at(1) == Some('"') => {
                self.bump();
                self.string();
                Some(Node { pos, end: self.pos(), kind: Kind::Atom })
            }
            'b' if self.peek_at(1) == Some('\'') => {
                self.bump();
                self.char_literal();
                Some(Node { pos, end: self.pos(), kind: Kind::Atom })
            }
            c if Self::is_ident_start(c) || (c == 'r' && self.peek_at(1) == Some('#')) => {
                self.ident()?;
                self.skip_ws();
                if self.peek() == Some('(') {
                    let kind = self.parens(depth)?;
                    Some(Node { pos, end: self.pos(), kind })
                } else {
                    Some(Node { pos, end: self.pos(), kind: Kind::Atom })
                }
            }
            c if c.is_ascii_digit() || c == '-' || c == '+' || c == '.' => {
                self.bump();
                while self.peek().is_some_and(|c| {
                    c.is_ascii_alphanumeric() || c == '_' || c == '.' || c == '+' || c == '-'
                }) {
                    // Signs inside a number only follow an exponent.
                    let prev = self.src[..self.i].chars().next_back().unwrap_or(' ');
                    let c = self.peek().unwrap_or(' ');
                    if (c == '+' || c == '-') && !matches!(prev, 'e' | 'E') {
                        break;
                    }
                    self.bump();
                }
                Some(Node { pos, end: self.pos(), kind: Kind::Atom })
            }
            _ => None,
        }
    }

    /// `( ... )`: a struct when it starts with `name:`, a tuple otherwise. At the `(`.
    fn parens(&mut self, depth: usize) -> Option<Kind> {
        self.bump();
        self.skip_ws();
        if self.starts_field() {
            let mut fields = Vec::new();
            loop {
                self.skip_ws();
                if self.peek() == Some(')') {
                    self.bump();
                    return Some(Kind::Struct(fields));
                }
                let at = self.pos();
                let name = self.ident()?;
                self.skip_ws();
                if self.bump()? != ':' {
                    return None;
                }
                let value = self.value(depth + 1)?;
                if self.keep(fields.len(), true) {
                    fields.push((name, at, value));
                }
                self.skip_ws();
                match self.bump()? {
                    ',' => {}
                    ')' => return Some(Kind::Struct(fields)),
                    _ => return None,
                }
            }
        }
        self.items(')', depth).map(Kind::Tuple)
    }

    /// Whether the next tokens are `identifier :` (and not `identifier ::`).
    fn starts_field(&self) -> bool {
        let raw = self.peek() == Some('r') && self.peek_at(1) == Some('#');
        let mut k = if raw { 2 } else { 0 };
        if !raw && !self.peek().is_some_and(Self::is_ident_start) {
            return false;
        }
        while self.peek_at(k).is_some_and(|c| Self::is_ident_char(c) || (raw && matches!(c, '.' | '+' | '-')))
        {
            k += 1;
        }
        while self.peek_at(k).is_some_and(char::is_whitespace) {
            k += 1;
        }
        self.peek_at(k) == Some(':') && self.peek_at(k + 1) != Some(':')
    }

    /// Comma-separated values up to `end` (after the opening bracket).
    fn items(&mut self, end: char, depth: usize) -> Option<Vec<Node>> {
        let mut items = Vec::new();
        loop {
            self.skip_ws();
            if self.peek() == Some(end) {
                self.bump();
                return Some(items);
            }
            let v = self.value(depth + 1)?;
            if self.keep(items.len(), end == ')') {
                items.push(v);
            }
            self.skip_ws();
            let c = self.bump()?;
            if c == end {
                return Some(items);
            }
            if c != ',' {
                return None;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(src: &str, path: &[Seg]) -> (usize, usize) {
        let p = Tree::parse(src).position(path);
        (p.line, p.column)
    }

    #[test]
    fn finds_fields_through_variants_and_some() {
        let src = "Scene(\n  title: \"x\", // c\n  tissue: Layers((\n    layers: [ (a: 1), (a: /* x */ 2.5e-3) ],\n    c: Some((m: 4)),\n  )),\n)";
        assert_eq!(at(src, &[Seg::Field("title")]), (2, 10));
        let p = [Seg::Field("tissue"), Seg::Field("layers"), Seg::Index(1), Seg::Field("a")];
        assert_eq!(at(src, &p), (4, 35));
        assert_eq!(at(src, &[Seg::Field("tissue"), Seg::Field("c"), Seg::Field("m")]), (5, 17));
        // A field the source leaves out: the deepest value found.
        assert_eq!(at(src, &[Seg::Field("tissue"), Seg::Field("resolution")]), (3, 11));
    }

    #[test]
    fn indexes_into_named_tuples() {
        let src = "Script([\n  Wait(3),\n  Grasp(Surface(0.5, 1.5, 0.0)),\n])";
        assert_eq!(at(src, &[Seg::Inner, Seg::Index(0), Seg::Index(0)]), (2, 8));
        assert_eq!(at(src, &[Seg::Inner, Seg::Index(1), Seg::Inner, Seg::Index(1)]), (3, 22));
    }

    #[test]
    fn a_huge_list_keeps_a_bounded_tree() {
        let n = MAX_NODES + 10;
        let src = format!("(t: ((a: [{}],\n b: (7, 8))))", "0.5, ".repeat(n));
        // Items past the limit are not kept: their path ends at the list.
        let a = [Seg::Field("t"), Seg::Field("a")];
        assert_eq!(at(&src, &[a[0], a[1], Seg::Index(n - 1)]), (1, 10));
        assert_eq!(at(&src, &[a[0], a[1], Seg::Index(3)]), (1, 26));
        // What follows the list is still found, and the list itself.
        assert_eq!(at(&src, &[Seg::Field("t"), Seg::Field("b"), Seg::Index(1)]), (2, 9));
    }

    #[test]
    fn columns_count_characters_not_bytes() {
        assert_eq!(at("(é: \"ü\", a: 1)", &[Seg::Field("a")]), (1, 13));
    }

    #[test]
    fn never_fails_on_garbage() {
        for src in ["", "(", "(a: ", "r#\"", "/* ", "[1, 2", "#![enable(implicit_some)] (a: 1)"] {
            let _ = Tree::parse(src).position(&[Seg::Field("a"), Seg::Index(3)]);
        }
    }
}
