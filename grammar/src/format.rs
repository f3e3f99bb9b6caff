//! The canonical layout of a `.pack` file: one statement per line, blocks
//! indented by two spaces, single spaces between tokens, numbers and units
//! as written, comments kept (own-line comments before what follows them,
//! trailing comments after their line, two spaces before `#`), and at most
//! one blank line wherever the source had one or more. Idempotent.

use crate::ast::*;
use crate::error::SyntaxError;
use crate::parser::parse;
use crate::span::Span;

/// Formats a text; fails with its syntax errors if it does not parse.
pub fn format(src: &str) -> Result<String, Vec<SyntaxError>> {
    let file = parse(src)?;
    Ok(format_file(src, &file))
}

/// Formats a parsed file; `src` is the text it was parsed from (for
/// comments and blank lines).
pub fn format_file(src: &str, file: &File) -> String {
    let mut p = Printer {
        src,
        comments: scan_comments(src),
        next_comment: 0,
        lines: Vec::new(),
        last_end: None,
    };
    for item in &file.items {
        p.item(item);
    }
    p.own_line_comments_before(src.len(), 0);
    p.finish()
}

struct Comment {
    start: usize,
    text: String,
    /// Only white space stands before it on its line.
    own_line: bool,
}

/// Finds every `#` comment outside string literals.
fn scan_comments(src: &str) -> Vec<Comment> {
    let mut out = Vec::new();
    let mut in_string = false;
    let mut escaped = false;
    let mut line_start = 0;
    let mut iter = src.char_indices();
    while let Some((i, c)) = iter.next() {
        match c {
            '\n' | '\r' => {
                in_string = false;
                line_start = i + 1;
            }
            '\\' if in_string && !escaped => {
                escaped = true;
                continue;
            }
            '"' if !escaped => in_string = !in_string,
            '#' if !in_string => {
                let end = src[i..].find(['\n', '\r']).map_or(src.len(), |e| i + e);
                out.push(Comment {
                    start: i,
                    text: src[i..end].trim_end().to_owned(),
                    own_line: src[line_start..i].trim().is_empty(),
                });
                // Skip to the line break (kept for the `\n` arm).
                while let Some((j, _)) = iter.clone().next() {
                    if j >= end {
                        break;
                    }
                    iter.next();
                }
            }
            _ => {}
        }
        escaped = false;
    }
    out
}

struct Line {
    indent: usize,
    text: String,
    blank_before: bool,
}

struct Printer<'a> {
    src: &'a str,
    comments: Vec<Comment>,
    next_comment: usize,
    lines: Vec<Line>,
    /// Source end of the last thing printed (for blank-line detection);
    /// `None` at the start of the file or of a block.
    last_end: Option<usize>,
}

impl Printer<'_> {
    fn finish(self) -> String {
        let mut out = String::new();
        for (i, line) in self.lines.iter().enumerate() {
            if line.blank_before && i > 0 {
                out.push('\n');
            }
            for _ in 0..line.indent {
                out.push_str("  ");
            }
            out.push_str(&line.text);
            out.push('\n');
        }
        out
    }

    /// Did the source have a blank line between the last printed thing and
    /// `start`?
    fn blank_gap(&self, start: usize) -> bool {
        let Some(end) = self.last_end else {
            return false;
        };
        let gap = self.src.get(end..start).unwrap_or("");
        let pieces: Vec<&str> = gap.split('\n').collect();
        pieces.len() > 2
            && pieces[1..pieces.len() - 1]
                .iter()
                .any(|l| l.trim().is_empty())
    }

    fn push(&mut self, indent: usize, text: String, span: Span) {
        let blank_before = self.blank_gap(span.start as usize);
        self.lines.push(Line {
            indent,
            text,
            blank_before,
        });
        self.last_end = Some(span.end as usize);
        self.trailing_comment(span.end as usize);
    }

    /// Appends a comment that follows `end` on the same source line.
    fn trailing_comment(&mut self, end: usize) {
        while let Some(c) = self.comments.get(self.next_comment) {
            if c.own_line || c.start < end {
                return;
            }
            let between = self.src.get(end..c.start).unwrap_or("");
            if between.contains('\n') {
                return;
            }
            let text = c.text.clone();
            let start = c.start;
            self.next_comment += 1;
            if let Some(line) = self.lines.last_mut() {
                line.text.push_str("  ");
                line.text.push_str(&text);
            }
            self.last_end = Some(start + text.len());
        }
    }

    /// Prints the comments that start before `pos`, each on its own line.
    /// A trailing comment whose construct printed nothing (a stray `;`)
    /// becomes an own-line comment too.
    fn own_line_comments_before(&mut self, pos: usize, indent: usize) {
        while let Some(c) = self.comments.get(self.next_comment) {
            if c.start >= pos {
                return;
            }
            let (start, text) = (c.start, c.text.clone());
            self.next_comment += 1;
            let blank_before = self.blank_gap(start);
            self.lines.push(Line {
                indent,
                text,
                blank_before,
            });
            self.last_end = Some(start + self.comments[self.next_comment - 1].text.len());
        }
    }

    fn line(&mut self, indent: usize, text: String, span: Span) {
        self.own_line_comments_before(span.start as usize, indent);
        self.push(indent, text, span);
    }

    /// A block: header line, statements, closing brace.
    fn block<T>(
        &mut self,
        header: String,
        span: Span,
        stmts: &[Stmt<T>],
        fmt: impl Fn(&T) -> String,
    ) {
        self.own_line_comments_before(span.start as usize, 0);
        let blank_before = self.blank_gap(span.start as usize);
        self.lines.push(Line {
            indent: 0,
            text: format!("{header} {{"),
            blank_before,
        });
        // The header's trailing comment sits after `{` on the header line.
        let header_end = self.src[span.range()]
            .find('{')
            .map_or(span.start as usize, |i| span.start as usize + i + 1);
        self.last_end = Some(header_end);
        self.trailing_comment(header_end);
        self.last_end = None;
        for st in stmts {
            self.line(1, fmt(&st.kind), st.span);
        }
        let close = (span.end as usize).saturating_sub(1);
        self.own_line_comments_before(close, 1);
        self.lines.push(Line {
            indent: 0,
            text: "}".into(),
            blank_before: false,
        });
        self.last_end = Some(span.end as usize);
        self.trailing_comment(span.end as usize);
    }

    fn item(&mut self, item: &Item) {
        match item {
            Item::Use(u) => self.line(0, format!("use {}", string(&u.path)), u.span),
            Item::Product(p) => {
                let shape = match &p.shape {
                    Shape::Cube(l) => format!("cube {}", length(l)),
                    Shape::Box(s) => format!("box {}", point(s)),
                };
                let mass = p
                    .mass
                    .as_ref()
                    .map_or(String::new(), |m| format!(" mass {}", mass(m)));
                self.line(0, format!("product {} {shape}{mass}", p.name.text), p.span);
            }
            Item::Cell(c) => {
                self.block(format!("cell {}", c.name.text), c.span, &c.stmts, cell_stmt)
            }
            Item::Inventory(i) => self.block(
                format!("inventory {} for {}", i.name.text, i.cell.text),
                i.span,
                &i.entries,
                |e| format!("{} {}", e.product.text, point(&e.at)),
            ),
            Item::Order(o) => self.block(
                format!("order {} for {}", o.name.text, o.inventory.text),
                o.span,
                &o.stmts,
                |s| match s {
                    OrderStmt::Customer(c) => format!("customer {}", string(c)),
                    OrderStmt::Batch(b) => format!("batch {}", b.value),
                    OrderStmt::Assign { product, slot } => {
                        format!("{} -> {}", product.text, slot.text)
                    }
                },
            ),
            Item::Demo(d) => self.block(
                format!("demo {} for {}", d.name.text, d.order.text),
                d.span,
                &d.stmts,
                |s| match s {
                    DemoStmt::Sequence(ns) => format!("sequence {}", names(ns)),
                    DemoStmt::At { product, at } => format!("at {} {}", product.text, point(at)),
                },
            ),
            Item::Demos(d) => self.block(
                format!("demos {} for {}", d.name.text, d.inventory.text),
                d.span,
                &d.stmts,
                |s| match s {
                    DemosStmt::Choose(c) => choose(c),
                    DemosStmt::Keep(f) => format!("keep {}", f.number),
                    DemosStmt::Jitter(l) => format!("jitter {}", length(l)),
                    DemosStmt::Sequence(m) => format!("sequence {}", m.as_str()),
                    DemosStmt::Repeat(c) => format!("repeat {}", c.value),
                    DemosStmt::Seed(c) => format!("seed {}", c.value),
                    DemosStmt::HumanPacks(r) => format!("human packs {}", range(r)),
                    DemosStmt::Missing(r) => format!("missing {}", range(r)),
                },
            ),
            Item::Scenario(sc) => self.block(
                format!("scenario {} for {}", sc.name.text, sc.order.text),
                sc.span,
                &sc.stmts,
                |s| match s {
                    ScenarioStmt::HumanPacked(ns) => format!("human packed {}", names(ns)),
                    ScenarioStmt::Missing(ns) => format!("missing {}", names(ns)),
                    ScenarioStmt::Jitter(l) => format!("jitter {}", length(l)),
                    ScenarioStmt::Seed(c) => format!("seed {}", c.value),
                    ScenarioStmt::At { product, at } => {
                        format!("at {} {}", product.text, point(at))
                    }
                },
            ),
            Item::Scenarios(sc) => self.block(
                format!("scenarios {} for {}", sc.name.text, sc.inventory.text),
                sc.span,
                &sc.stmts,
                |s| match s {
                    ScenariosStmt::Choose(c) => choose(c),
                    ScenariosStmt::HumanPacks(r) => format!("human packs {}", range(r)),
                    ScenariosStmt::Missing(r) => format!("missing {}", range(r)),
                    ScenariosStmt::Jitter(l) => format!("jitter {}", length(l)),
                    ScenariosStmt::Count(c) => format!("count {}", c.value),
                    ScenariosStmt::Seed(c) => format!("seed {}", c.value),
                },
            ),
        }
    }
}

fn cell_stmt(s: &CellStmt) -> String {
    match s {
        CellStmt::Robot(Robot::Ur10) => "robot ur10".into(),
        CellStmt::Robot(Robot::Urdf(path)) => format!("robot urdf {}", string(path)),
        CellStmt::Base(p) => format!("base {}", point(p)),
        CellStmt::Suction(l) => format!("suction {}", length(l)),
        CellStmt::Pending(a, b) => format!("pending {} to {}", point(a), point(b)),
        CellStmt::Box { name, at, size } => {
            format!("box {} {} size {}", name.text, point(at), point(size))
        }
        CellStmt::Slot { name, at } => format!("slot {} {}", name.text, point(at)),
        CellStmt::Lift(l) => format!("lift {}", length(l)),
        CellStmt::Speed(s) if s.percent => format!("speed {} %", s.number),
        CellStmt::Speed(s) => format!("speed {}", s.number),
        CellStmt::Descent(s) if s.percent => format!("descent {} %", s.number),
        CellStmt::Descent(s) => format!("descent {}", s.number),
        CellStmt::Acceleration(v) => format!("acceleration {}", joint_values(v)),
        CellStmt::Jerk(v) => format!("jerk {}", joint_values(v)),
        CellStmt::Settle { time: t, after } => {
            format!("settle {} after {}", time(t), after.as_str())
        }
    }
}

fn length(l: &Length) -> String {
    match l.unit {
        Some(u) => format!("{} {}", l.number, u.as_str()),
        None => l.number.clone(),
    }
}

fn joint_values(v: &JointValues) -> String {
    let numbers: Vec<&str> = v.values.iter().map(|f| f.number.as_str()).collect();
    format!("({})", numbers.join(", "))
}

fn time(t: &Time) -> String {
    match t.unit {
        Some(u) => format!("{} {}", t.number, u.as_str()),
        None => t.number.clone(),
    }
}

fn mass(m: &Mass) -> String {
    match m.unit {
        Some(u) => format!("{} {}", m.number, u.as_str()),
        None => m.number.clone(),
    }
}

fn point(p: &Point) -> String {
    match &p.z {
        Some(z) => format!("({}, {}, {})", length(&p.x), length(&p.y), length(z)),
        None => format!("({}, {})", length(&p.x), length(&p.y)),
    }
}

fn names(ns: &[Name]) -> String {
    ns.iter()
        .map(|n| n.text.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

fn choose(c: &Choose) -> String {
    format!(
        "choose {} of {} into {}",
        c.n.value,
        names(&c.products),
        names(&c.slots)
    )
}

fn range(r: &Range) -> String {
    format!("{} to {}", r.low.value, r.high.value)
}

fn string(s: &Str) -> String {
    let mut out = String::from("\"");
    for c in s.value.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_and_comments() {
        let src = "# head\n\n\n\ncell  c {   # the cell\n robot ur10;base (0,0,0)\n\n   # about slots\n  slot g1 ( 0.1 , 0.2 )   # first\n}\nproduct A cube 50mm mass 300 g\n# tail\n";
        let out = format(src).unwrap();
        assert_eq!(
            out,
            "# head\n\ncell c {  # the cell\n  robot ur10\n  base (0, 0, 0)\n\n  # about slots\n  slot g1 (0.1, 0.2)  # first\n}\nproduct A cube 50 mm mass 300 g\n# tail\n"
        );
        assert_eq!(format(&out).unwrap(), out);
    }

    #[test]
    fn hash_inside_string_is_not_a_comment() {
        let src = "order o for i {\n  customer \"No #1 \\\"Ltd\\\"\"  # real\n}\n";
        let out = format(src).unwrap();
        assert_eq!(out, src);
    }
}
