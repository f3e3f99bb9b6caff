//! A tiny SVG writer: elements appended to a string, numbers in one fixed
//! format, text escaped. Guarantees: the same calls give the same bytes;
//! every number is written with one decimal (`-0.0` as `0.0`); attribute
//! values and text are XML-escaped.

use std::fmt::Write;

/// A number as SVG text: one decimal, no negative zero.
pub fn num(v: f64) -> String {
    let s = format!("{v:.1}");
    if s == "-0.0" { "0.0".into() } else { s }
}

/// `s` with `&`, `<`, `>`, `"` and `'` escaped.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Attributes of one element, in the order given.
#[derive(Debug, Default, Clone)]
pub struct Attrs(String);

impl Attrs {
    pub fn new() -> Attrs {
        Attrs::default()
    }

    /// A text attribute (escaped).
    pub fn s(mut self, name: &str, value: &str) -> Attrs {
        let _ = write!(self.0, " {name}=\"{}\"", escape(value));
        self
    }

    /// A number attribute (one decimal).
    pub fn n(mut self, name: &str, value: f64) -> Attrs {
        let _ = write!(self.0, " {name}=\"{}\"", num(value));
        self
    }
}

/// An SVG document being written.
#[derive(Debug)]
pub struct Svg {
    body: String,
    width: f64,
    height: f64,
}

impl Svg {
    pub fn new(width: f64, height: f64) -> Svg {
        Svg {
            body: String::new(),
            width,
            height,
        }
    }

    /// An empty element `<name .../>`.
    pub fn el(&mut self, name: &str, attrs: Attrs) {
        let _ = writeln!(self.body, "<{name}{}/>", attrs.0);
    }

    /// `<text ...>text</text>`.
    pub fn text(&mut self, attrs: Attrs, text: &str) {
        let _ = writeln!(self.body, "<text{}>{}</text>", attrs.0, escape(text));
    }

    /// Opens `<g ...>`; close with [`Svg::end`].
    pub fn group(&mut self, attrs: Attrs) {
        let _ = writeln!(self.body, "<g{}>", attrs.0);
    }

    pub fn end(&mut self) {
        self.body.push_str("</g>\n");
    }

    /// A `<title>` for the element just opened (tooltips in browsers).
    pub fn title(&mut self, text: &str) {
        let _ = writeln!(self.body, "<title>{}</title>", escape(text));
    }

    /// Raw markup (the caller guarantees it is well formed).
    pub fn raw(&mut self, markup: &str) {
        self.body.push_str(markup);
    }

    /// The whole document.
    pub fn finish(self) -> String {
        let (w, h) = (num(self.width), num(self.height));
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\">\n{}</svg>\n",
            self.body
        )
    }
}

/// Points as an SVG `points` list.
pub fn points(ps: &[(f64, f64)]) -> String {
    ps.iter()
        .map(|(x, y)| format!("{},{}", num(*x), num(*y)))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_fixed_and_never_negative_zero() {
        assert_eq!(num(1.0), "1.0");
        assert_eq!(num(-0.01), "0.0");
        assert_eq!(num(2.345), "2.3");
        assert_eq!(num(-12.36), "-12.4");
    }

    #[test]
    fn text_and_attributes_are_escaped() {
        let mut svg = Svg::new(10.0, 10.0);
        svg.text(Attrs::new().s("class", "a\"b"), "<x & y>");
        let out = svg.finish();
        assert!(out.contains("class=\"a&quot;b\""));
        assert!(out.contains("&lt;x &amp; y&gt;"));
    }
}
