//! A cell in top and side view at true scale: the robot base and its
//! reachable annulus, the pending area, the boxes and their slots (names
//! and labels), products with their footprints, an order's assignment as
//! arrows, worker-packed and missing products, diagnostics where they are,
//! and an executed tool path.
//!
//! Guarantees: one `<g class="product">` per product and one
//! `<g class="slot">` per slot (in the top view; the side view's are
//! `product-side` and `slot-side`), each with an `id` from its name; one
//! `class="diagnostic"` element per mark; the output depends on the input
//! alone (no clock, fixed number format).

use crate::error::DrawError;
use crate::path::{self, EventKind, Stage, ToolPath};
use crate::svg::{Attrs, Svg, num};
use crate::view::{SCALE, Span, View, grid, label};
use packwright_interface::scene::CellScene;

const MARGIN: f64 = 48.0;
const TITLE: f64 = 30.0;
const GAP: f64 = 44.0;
const LINE: f64 = 16.0;
/// Drawn radius of the robot base (m).
const BASE_RADIUS: f64 = 0.09;
/// Height of the base link above its mounting (m), for the side view.
const BASE_HEIGHT: f64 = 0.128;
const RED: &str = "#d62728";

/// What a product is doing in the picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProductState {
    /// On the table where the robot finds it.
    Waiting,
    /// In its slot already, packed by a worker.
    WorkerPacked,
    /// Out of stock: drawn dashed where it would stand.
    Missing,
}

impl ProductState {
    fn class(self) -> &'static str {
        match self {
            ProductState::Waiting => "waiting",
            ProductState::WorkerPacked => "worker-packed",
            ProductState::Missing => "missing",
        }
    }
}

/// A product to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct Product {
    pub name: String,
    /// Width (x), depth (y), height (z).
    pub size: [f64; 3],
    /// Its centre (world frame).
    pub centre: [f64; 3],
    pub state: ProductState,
}

/// Where a diagnostic is drawn.
#[derive(Debug, Clone, PartialEq)]
pub enum Place {
    /// Index into the cell's slots.
    Slot(usize),
    /// Index into [`Picture::products`].
    Product(usize),
    /// Index into the cell's boxes.
    Box(usize),
    /// A point (world frame), e.g. an unreachable tool tip.
    Point([f64; 3]),
    /// Nowhere in particular: listed under the picture only.
    Cell,
}

/// A diagnostic to draw (red) where it is, and list under the picture.
#[derive(Debug, Clone, PartialEq)]
pub struct Mark {
    pub place: Place,
    /// Its code, e.g. `E030`.
    pub code: String,
    pub message: String,
}

/// The reachable annulus about the base axis (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    pub min: f64,
    pub max: f64,
}

/// The UR10's annulus (the compiler's E036 check).
pub const UR10_REACH: Reach = Reach {
    min: 0.20,
    max: 1.30,
};

/// Everything one picture shows.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    pub title: String,
    pub cell: CellScene,
    pub reach: Option<Reach>,
    pub products: Vec<Product>,
    /// (index into `products`, index into the cell's slots): arrows from
    /// the product to its slot (none for worker-packed products).
    pub assignment: Vec<(usize, usize)>,
    pub marks: Vec<Mark>,
    pub path: Option<ToolPath>,
}

impl Picture {
    /// The cell alone.
    pub fn new(title: impl Into<String>, cell: CellScene) -> Picture {
        Picture {
            title: title.into(),
            cell,
            reach: None,
            products: Vec::new(),
            assignment: Vec::new(),
            marks: Vec::new(),
            path: None,
        }
    }
}

fn check(picture: &Picture) -> Result<(), DrawError> {
    let bad = |what: String| Err(DrawError::NonFinite { what });
    let c = &picture.cell;
    let all = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if !all(&c.base) || !all(&c.pending.0) || !all(&c.pending.1) {
        return bad(format!("cell `{}`", c.name));
    }
    for b in &c.boxes {
        if !all(&b.centre) || !all(&b.size) {
            return bad(format!("box `{}`", b.name));
        }
    }
    for s in &c.slots {
        if !all(&s.position) {
            return bad(format!("slot `{}`", s.name));
        }
    }
    for p in &picture.products {
        if !all(&p.centre) || !all(&p.size) {
            return bad(format!("product `{}`", p.name));
        }
    }
    if let Some(path) = &picture.path
        && (path.points.iter().any(|(p, _)| !all(p)) || path.events.iter().any(|e| !all(&e.at)))
    {
        return bad("the tool path".into());
    }
    if let Some(r) = picture.reach
        && !(r.min.is_finite() && r.max.is_finite())
    {
        return bad("the reach".into());
    }
    for &(p, s) in &picture.assignment {
        if p >= picture.products.len() || s >= c.slots.len() {
            return Err(DrawError::BadIndex {
                what: format!("assignment ({p}, {s})"),
            });
        }
    }
    Ok(())
}

/// The longest extent (m) a picture holds along any axis: at true scale
/// ([`SCALE`] pixels a metre) a longer one would be a picture of millions
/// of pixels with a grid line every 0.1 m, and a cell is a few metres.
pub const MAX_SPAN: f64 = 50.0;

/// The picture as an SVG document: the top view, the side view below it
/// (looking across the longer horizontal extent of the cell's contents),
/// and a legend with every diagnostic.
pub fn picture(picture: &Picture) -> Result<String, DrawError> {
    check(picture)?;
    let c = &picture.cell;
    // What the views must hold.
    let mut bounds = [Span::empty(); 3];
    let add = |b: &mut [Span; 3], p: [f64; 3]| {
        for (span, v) in b.iter_mut().zip(p) {
            span.add(v);
        }
    };
    add(&mut bounds, [c.pending.0[0], c.pending.0[1], 0.0]);
    add(&mut bounds, [c.pending.1[0], c.pending.1[1], 0.0]);
    for b in &c.boxes {
        add(
            &mut bounds,
            [
                b.centre[0] - b.size[0] / 2.0,
                b.centre[1] - b.size[1] / 2.0,
                0.0,
            ],
        );
        add(
            &mut bounds,
            [
                b.centre[0] + b.size[0] / 2.0,
                b.centre[1] + b.size[1] / 2.0,
                b.size[2],
            ],
        );
    }
    for s in &c.slots {
        add(&mut bounds, [s.position[0], s.position[1], 0.0]);
    }
    for p in &picture.products {
        let [cx, cy, cz] = p.centre;
        add(
            &mut bounds,
            [
                cx - p.size[0] / 2.0,
                cy - p.size[1] / 2.0,
                cz - p.size[2] / 2.0,
            ],
        );
        add(
            &mut bounds,
            [
                cx + p.size[0] / 2.0,
                cy + p.size[1] / 2.0,
                cz + p.size[2] / 2.0,
            ],
        );
    }
    for m in &picture.marks {
        if let Place::Point(p) = m.place {
            add(&mut bounds, p);
        }
    }
    // The side view looks across the longer extent of the contents.
    let side_h = if bounds[1].len() > bounds[0].len() {
        1
    } else {
        0
    };
    if let Some(path) = &picture.path {
        for (p, _) in &path.points {
            add(&mut bounds, *p);
        }
    }
    let reach = picture.reach.map_or(BASE_RADIUS, |r| r.max);
    add(
        &mut bounds,
        [
            c.base[0] - reach,
            c.base[1] - reach,
            c.base[2] + BASE_HEIGHT,
        ],
    );
    add(&mut bounds, [c.base[0] + reach, c.base[1] + reach, 0.0]);
    for (span, axis) in bounds.iter().zip(['x', 'y', 'z']) {
        if span.len() > MAX_SPAN {
            return Err(DrawError::TooLarge {
                axis,
                metres: span.len(),
                max: MAX_SPAN,
            });
        }
    }
    let [xs, ys, zs] = bounds;
    let (xs, ys) = (xs.grown(0.05), ys.grown(0.05));
    let zs = Span {
        lo: zs.lo.min(0.0) - 0.05,
        hi: zs.hi.max(0.0) + 0.08,
    };
    let top = View {
        h: 0,
        v: 1,
        hs: xs,
        vs: ys,
        left: MARGIN,
        top: TITLE + LINE,
    };
    let side = View {
        h: side_h,
        v: 2,
        hs: if side_h == 0 { xs } else { ys },
        vs: zs,
        left: MARGIN,
        top: top.top + top.height() + GAP + LINE,
    };
    let legend = legend_lines(picture);
    // Legend text at 12 px is about 6.6 px a character.
    let text = legend
        .iter()
        .map(|(t, _)| t.chars().count() as f64 * 6.6)
        .fold(560.0, f64::max);
    let width = MARGIN * 2.0 + top.width().max(side.width()).max(text);
    let height = side.top + side.height() + GAP + LINE * legend.len() as f64;
    let mut svg = Svg::new(width, height);
    svg.raw(concat!(
        "<defs><marker id=\"arrow\" viewBox=\"0 0 10 10\" refX=\"9\" refY=\"5\" ",
        "markerWidth=\"7\" markerHeight=\"7\" orient=\"auto-start-reverse\">",
        "<path d=\"M 0 0 L 10 5 L 0 10 z\" fill=\"#1f77b4\"/></marker></defs>\n",
    ));
    svg.el(
        "rect",
        Attrs::new()
            .n("x", 0.0)
            .n("y", 0.0)
            .n("width", width)
            .n("height", height)
            .s("fill", "white"),
    );
    svg.text(
        Attrs::new()
            .s("class", "title")
            .n("x", MARGIN)
            .n("y", 20.0)
            .n("font-size", 15.0),
        &picture.title,
    );
    svg.text(
        Attrs::new()
            .n("x", MARGIN)
            .n("y", top.top - 6.0)
            .n("font-size", 12.0),
        "top view (x right, y up; grid 0.1 m)",
    );
    let side_name = if side_h == 0 {
        "side view from -y (x right, z up)"
    } else {
        "side view from +x (y right, z up)"
    };
    svg.text(
        Attrs::new()
            .n("x", MARGIN)
            .n("y", side.top - 6.0)
            .n("font-size", 12.0),
        side_name,
    );
    grid(&mut svg, &top);
    grid(&mut svg, &side);
    draw_top(&mut svg, picture, &top);
    draw_side(&mut svg, picture, &side);
    if let Some(path) = &picture.path {
        path::draw(&mut svg, path, &top, "top");
        path::draw(&mut svg, path, &side, "side");
    }
    let mut y = side.top + side.height() + GAP;
    for (text, colour) in legend {
        svg.text(
            Attrs::new()
                .s("class", "legend")
                .n("x", MARGIN)
                .n("y", y)
                .n("font-size", 12.0)
                .s("fill", colour),
            &text,
        );
        y += LINE;
    }
    Ok(svg.finish())
}

fn draw_top(svg: &mut Svg, picture: &Picture, view: &View) {
    let c = &picture.cell;
    let base = c.base;
    let (bx, by) = view.px(base);
    if let Some(r) = picture.reach {
        let ring = |radius: f64| {
            let r = radius * SCALE;
            format!(
                "M {} {} a {} {} 0 1 0 {} 0 a {} {} 0 1 0 {} 0 Z",
                num(bx - r),
                num(by),
                num(r),
                num(r),
                num(2.0 * r),
                num(r),
                num(r),
                num(-2.0 * r)
            )
        };
        svg.group(Attrs::new().s("class", "reach"));
        svg.title(&format!(
            "reachable annulus {} m to {} m from the base axis",
            r.min, r.max
        ));
        svg.el(
            "path",
            Attrs::new()
                .s("d", &format!("{} {}", ring(r.max), ring(r.min)))
                .s("fill", "#e8f5e9")
                .s("fill-rule", "evenodd")
                .s("stroke", "#81c784")
                .s("stroke-dasharray", "6 4"),
        );
        label(
            svg,
            (bx, by - r.max * SCALE + 14.0),
            11.0,
            "middle",
            &format!("reach {:.2} to {:.2} m", r.min, r.max),
        );
        svg.end();
    }
    svg.group(Attrs::new().s("class", "base"));
    svg.el(
        "circle",
        Attrs::new()
            .n("cx", bx)
            .n("cy", by)
            .n("r", BASE_RADIUS * SCALE)
            .s("fill", "#555555"),
    );
    svg.text(
        Attrs::new()
            .n("x", bx)
            .n("y", by + 4.0)
            .n("font-size", 11.0)
            .s("text-anchor", "middle")
            .s("fill", "white"),
        "base",
    );
    svg.end();
    let (lo, hi) = c.pending;
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, 0.0];
    svg.group(Attrs::new().s("class", "pending"));
    svg.el(
        "rect",
        view.rect(centre, hi[0] - lo[0], hi[1] - lo[1])
            .s("fill", "#fffbe0")
            .s("stroke", "#c8b400")
            .s("stroke-dasharray", "4 3"),
    );
    let (x, y) = view.px([lo[0], hi[1], 0.0]);
    label(svg, (x + 2.0, y - 4.0), 11.0, "start", "pending area");
    svg.end();
    for b in &c.boxes {
        svg.group(
            Attrs::new()
                .s("class", "box")
                .s("id", &format!("box-{}", b.name)),
        );
        let centre = [b.centre[0], b.centre[1], 0.0];
        svg.el(
            "rect",
            view.rect(centre, b.size[0], b.size[1])
                .s("fill", "#f3e5d0")
                .s("stroke", "#8b5a2b")
                .n("stroke-width", 2.0),
        );
        let (x, y) = view.px([
            b.centre[0] - b.size[0] / 2.0,
            b.centre[1] + b.size[1] / 2.0,
            0.0,
        ]);
        label(svg, (x, y - 4.0), 11.0, "start", &format!("box {}", b.name));
        svg.end();
    }
    for (i, s) in c.slots.iter().enumerate() {
        let (x, y) = view.px([s.position[0], s.position[1], 0.0]);
        svg.group(
            Attrs::new()
                .s("class", "slot")
                .s("id", &format!("slot-{}", s.name)),
        );
        svg.title(&format!(
            "slot {} (label {}) at ({:.3}, {:.3})",
            s.name,
            i + 1,
            s.position[0],
            s.position[1]
        ));
        svg.el(
            "circle",
            Attrs::new()
                .n("cx", x)
                .n("cy", y)
                .n("r", 4.0)
                .s("fill", "none")
                .s("stroke", "#1a3d7c")
                .n("stroke-width", 1.5),
        );
        // The name under the slot, its label (index + 1) at its upper right:
        // slots 10 cm apart are 30 px apart.
        label(svg, (x, y + 14.0), 9.0, "middle", &s.name);
        svg.text(
            Attrs::new()
                .n("x", x + 5.0)
                .n("y", y - 4.0)
                .n("font-size", 8.0)
                .s("fill", "#1a3d7c"),
            &(i + 1).to_string(),
        );
        svg.end();
    }
    for (p, s) in &picture.assignment {
        let product = &picture.products[*p];
        if product.state == ProductState::WorkerPacked {
            continue;
        }
        let slot = &c.slots[*s];
        let (x1, y1) = view.px(product.centre);
        let (x2, y2) = view.px([slot.position[0], slot.position[1], 0.0]);
        let mut attrs = Attrs::new()
            .s("class", "assignment")
            .n("x1", x1)
            .n("y1", y1)
            .n("x2", x2)
            .n("y2", y2)
            .s("stroke", "#1f77b4")
            .n("stroke-width", 1.2)
            .s("marker-end", "url(#arrow)");
        if product.state == ProductState::Missing {
            attrs = attrs.s("stroke-dasharray", "4 3");
        }
        svg.el("line", attrs);
    }
    for p in &picture.products {
        svg.group(
            Attrs::new()
                .s("class", &format!("product {}", p.state.class()))
                .s("id", &format!("product-{}", p.name)),
        );
        svg.title(&format!(
            "{} ({}) at ({:.3}, {:.3}, {:.3}), {:.0} x {:.0} x {:.0} mm",
            p.name,
            p.state.class(),
            p.centre[0],
            p.centre[1],
            p.centre[2],
            p.size[0] * 1e3,
            p.size[1] * 1e3,
            p.size[2] * 1e3
        ));
        svg.el(
            "rect",
            product_style(view.rect(p.centre, p.size[0], p.size[1]), p.state),
        );
        let (x, y) = view.px(p.centre);
        let text = match p.state {
            ProductState::Waiting => p.name.clone(),
            ProductState::WorkerPacked => format!("{} (worker)", p.name),
            ProductState::Missing => format!("{} (missing)", p.name),
        };
        label(
            svg,
            (x, y - p.size[1] * SCALE / 2.0 - 3.0),
            10.0,
            "middle",
            &text,
        );
        svg.end();
    }
    marks(svg, picture, view);
}

fn product_style(attrs: Attrs, state: ProductState) -> Attrs {
    match state {
        ProductState::Waiting => attrs.s("fill", "#f4b183").s("stroke", "#a0522d"),
        ProductState::WorkerPacked => attrs.s("fill", "#b5d99c").s("stroke", "#4f7f2f"),
        ProductState::Missing => attrs
            .s("fill", "none")
            .s("stroke", "#888888")
            .s("stroke-dasharray", "3 2"),
    }
}

fn marks(svg: &mut Svg, picture: &Picture, view: &View) {
    let c = &picture.cell;
    for m in &picture.marks {
        let tag = format!("{} {}", m.code, m.message);
        let (shape, at) = match &m.place {
            Place::Slot(i) => match c.slots.get(*i) {
                Some(s) => {
                    let (x, y) = view.px([s.position[0], s.position[1], 0.0]);
                    (
                        ("circle", Attrs::new().n("cx", x).n("cy", y).n("r", 9.0)),
                        (x + 11.0, y - 6.0),
                    )
                }
                None => continue,
            },
            Place::Product(i) => match picture.products.get(*i) {
                Some(p) => {
                    let (x, y) = view.px(p.centre);
                    let grow = 6.0 / SCALE;
                    (
                        (
                            "rect",
                            view.rect(p.centre, p.size[0] + grow, p.size[1] + grow),
                        ),
                        (x + p.size[0] * SCALE / 2.0 + 5.0, y),
                    )
                }
                None => continue,
            },
            Place::Box(i) => match c.boxes.get(*i) {
                Some(b) => {
                    let centre = [b.centre[0], b.centre[1], 0.0];
                    let (x, y) = view.px(centre);
                    (
                        ("rect", view.rect(centre, b.size[0], b.size[1])),
                        (x + b.size[0] * SCALE / 2.0 + 5.0, y),
                    )
                }
                None => continue,
            },
            Place::Point(p) => {
                let (x, y) = view.px(*p);
                let d = format!(
                    "M {} {} L {} {} M {} {} L {} {}",
                    num(x - 6.0),
                    num(y - 6.0),
                    num(x + 6.0),
                    num(y + 6.0),
                    num(x - 6.0),
                    num(y + 6.0),
                    num(x + 6.0),
                    num(y - 6.0)
                );
                (("path", Attrs::new().s("d", &d)), (x + 8.0, y - 6.0))
            }
            Place::Cell => continue,
        };
        svg.group(Attrs::new().s("class", "diagnostic"));
        svg.title(&tag);
        svg.el(
            shape.0,
            shape
                .1
                .s("fill", "none")
                .s("stroke", RED)
                .n("stroke-width", 2.5),
        );
        svg.text(
            Attrs::new()
                .n("x", at.0)
                .n("y", at.1)
                .n("font-size", 11.0)
                .s("fill", RED)
                .s("font-weight", "bold"),
            &m.code,
        );
        svg.end();
    }
}

fn draw_side(svg: &mut Svg, picture: &Picture, view: &View) {
    let c = &picture.cell;
    let (x0, y0) = view.px([view.hs.lo, view.hs.lo, 0.0]);
    let x1 = view.left + view.width();
    svg.el(
        "line",
        Attrs::new()
            .s("class", "table")
            .n("x1", x0)
            .n("y1", y0)
            .n("x2", x1)
            .n("y2", y0)
            .s("stroke", "#999999")
            .n("stroke-width", 2.0),
    );
    let h = view.h;
    let base_top = c.base[2] + BASE_HEIGHT;
    svg.el(
        "rect",
        view.rect(
            [c.base[0], c.base[1], base_top / 2.0],
            2.0 * BASE_RADIUS,
            base_top,
        )
        .s("class", "base-side")
        .s("fill", "#555555"),
    );
    if let Some(r) = picture.reach {
        for d in [-r.max, -r.min, r.min, r.max] {
            let mut p = c.base;
            p[h] += d;
            let (x, _) = view.px(p);
            svg.el(
                "line",
                Attrs::new()
                    .s("class", "reach-side")
                    .n("x1", x)
                    .n("y1", view.top)
                    .n("x2", x)
                    .n("y2", y0)
                    .s("stroke", "#81c784")
                    .s("stroke-dasharray", "6 4"),
            );
        }
    }
    let (lo, hi) = c.pending;
    let (xa, ya) = view.px([lo[0], lo[1], 0.0]);
    let (xb, _) = view.px([hi[0], hi[1], 0.0]);
    svg.el(
        "line",
        Attrs::new()
            .s("class", "pending-side")
            .n("x1", xa)
            .n("y1", ya)
            .n("x2", xb)
            .n("y2", ya)
            .s("stroke", "#c8b400")
            .n("stroke-width", 4.0),
    );
    for bx in &c.boxes {
        let centre = [bx.centre[0], bx.centre[1], bx.size[2] / 2.0];
        svg.el(
            "rect",
            view.rect(centre, bx.size[h], bx.size[2])
                .s("class", "box-side")
                .s("fill", "#f3e5d0")
                .s("fill-opacity", "0.6")
                .s("stroke", "#8b5a2b")
                .n("stroke-width", 2.0),
        );
    }
    for s in &c.slots {
        let (x, y) = view.px([s.position[0], s.position[1], 0.0]);
        svg.el(
            "path",
            Attrs::new()
                .s("class", "slot-side")
                .s(
                    "d",
                    &format!(
                        "M {} {} L {} {} L {} {} Z",
                        num(x),
                        num(y),
                        num(x - 3.0),
                        num(y + 5.0),
                        num(x + 3.0),
                        num(y + 5.0)
                    ),
                )
                .s("fill", "#1a3d7c"),
        );
    }
    for p in &picture.products {
        svg.el(
            "rect",
            product_style(view.rect(p.centre, p.size[h], p.size[2]), p.state)
                .s("class", "product-side"),
        );
    }
}

/// The legend's lines (text, colour): what the symbols mean, the path's
/// stages and events, then every diagnostic.
fn legend_lines(picture: &Picture) -> Vec<(String, &'static str)> {
    let mut lines = vec![(
        "products: orange waiting, green packed by a worker, dashed missing; arrows: the order's assignment; slots: name below, label at the upper right".to_owned(),
        "#333333",
    )];
    if let Some(path) = &picture.path {
        lines.push((
            format!(
                "tool path: {} approach, {} carry, {} retreat; numbered circles: sub-goals (the arm stopped or slowed); black square: start",
                Stage::Approach.colour(),
                Stage::Carry.colour(),
                Stage::Retreat.colour()
            )
            .replace(Stage::Approach.colour(), "blue")
            .replace(Stage::Carry.colour(), "green")
            .replace(Stage::Retreat.colour(), "purple"),
            "#333333",
        ));
        for e in &path.events {
            match &e.kind {
                EventKind::Fallback(why) => {
                    lines.push((format!("orange diamond: fallback: {why}"), "#b35900"))
                }
                EventKind::Failure(why) => lines.push((format!("red cross: failure: {why}"), RED)),
                _ => {}
            }
        }
    }
    for m in &picture.marks {
        lines.push((format!("{}: {}", m.code, m.message), RED));
    }
    lines
}
