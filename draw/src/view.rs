//! A view of a picture: metres to pixels at true scale, its grid.

use crate::svg::{Attrs, Svg, num};

/// Pixels per metre (every view).
pub const SCALE: f64 = 300.0;

/// A closed range of metres.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Span {
    pub lo: f64,
    pub hi: f64,
}

impl Span {
    pub(crate) fn empty() -> Span {
        Span {
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
        }
    }
    pub(crate) fn add(&mut self, v: f64) {
        self.lo = self.lo.min(v);
        self.hi = self.hi.max(v);
    }
    pub(crate) fn len(&self) -> f64 {
        (self.hi - self.lo).max(0.0)
    }
    pub(crate) fn grown(self, by: f64) -> Span {
        Span {
            lo: self.lo - by,
            hi: self.hi + by,
        }
    }
}

/// A view's mapping from metres to pixels: horizontal axis `h` (0 = x,
/// 1 = y), vertical axis `v` (1 = y, 2 = z), the panel's origin.
#[derive(Debug, Clone, Copy)]
pub(crate) struct View {
    pub h: usize,
    pub v: usize,
    pub hs: Span,
    pub vs: Span,
    pub left: f64,
    pub top: f64,
}

impl View {
    pub(crate) fn px(&self, p: [f64; 3]) -> (f64, f64) {
        (
            self.left + (p[self.h] - self.hs.lo) * SCALE,
            self.top + (self.vs.hi - p[self.v]) * SCALE,
        )
    }
    pub(crate) fn width(&self) -> f64 {
        self.hs.len() * SCALE
    }
    pub(crate) fn height(&self) -> f64 {
        self.vs.len() * SCALE
    }
    /// A rectangle of metres (centre, sizes along h and v) in pixels.
    pub(crate) fn rect(&self, centre: [f64; 3], dh: f64, dv: f64) -> Attrs {
        let (x, y) = self.px(centre);
        Attrs::new()
            .n("x", x - dh * SCALE / 2.0)
            .n("y", y - dv * SCALE / 2.0)
            .n("width", dh * SCALE)
            .n("height", dv * SCALE)
    }
}

/// Grid lines every 0.1 m, labelled every 0.5 m, and the panel's frame.
pub(crate) fn grid(svg: &mut Svg, view: &View) {
    svg.group(
        Attrs::new()
            .s("class", "grid")
            .s("stroke", "#eeeeee")
            .n("stroke-width", 1.0),
    );
    let lines = |span: Span| {
        let first = (span.lo * 10.0).ceil() as i64;
        let last = (span.hi * 10.0).floor() as i64;
        (first..=last).map(|k| k as f64 / 10.0)
    };
    let (x0, y0) = (view.left, view.top);
    let (x1, y1) = (view.left + view.width(), view.top + view.height());
    let mut labels = Vec::new();
    for h in lines(view.hs) {
        let x = view.left + (h - view.hs.lo) * SCALE;
        svg.el(
            "line",
            Attrs::new().n("x1", x).n("y1", y0).n("x2", x).n("y2", y1),
        );
        if (h * 10.0).round() as i64 % 5 == 0 {
            labels.push((x, y1 + 13.0, "middle", h));
        }
    }
    for v in lines(view.vs) {
        let y = view.top + (view.vs.hi - v) * SCALE;
        svg.el(
            "line",
            Attrs::new().n("x1", x0).n("y1", y).n("x2", x1).n("y2", y),
        );
        if (v * 10.0).round() as i64 % 5 == 0 {
            labels.push((x0 - 4.0, y + 4.0, "end", v));
        }
    }
    svg.el(
        "rect",
        Attrs::new()
            .n("x", x0)
            .n("y", y0)
            .n("width", view.width())
            .n("height", view.height())
            .s("fill", "none")
            .s("stroke", "#bbbbbb"),
    );
    svg.end();
    for (x, y, anchor, v) in labels {
        svg.text(
            Attrs::new()
                .n("x", x)
                .n("y", y)
                .n("font-size", 10.0)
                .s("text-anchor", anchor)
                .s("fill", "#777777"),
            &format!("{} m", num(v)),
        );
    }
}

pub(crate) fn label(svg: &mut Svg, (x, y): (f64, f64), size: f64, anchor: &str, text: &str) {
    svg.text(
        Attrs::new()
            .n("x", x)
            .n("y", y)
            .n("font-size", size)
            .s("text-anchor", anchor),
        text,
    );
}
