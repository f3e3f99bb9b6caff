//! `packwright draw`: a cell (with an inventory, an order or a scenario)
//! as an SVG picture, diagnostics drawn where they are
//! (`packwright_draw` does the drawing; this is the edge: files in,
//! diagnostics mapped to places, the picture out).

use crate::Exit;
use crate::cli::DrawArgs;
use crate::fsio::{FsLoader, write_file_atomically};
use anyhow::bail;
use nalgebra::Isometry3;
use packwright_compiler::emit::cell_record;
use packwright_compiler::expand::{self, Setup};
use packwright_compiler::model::{Model, RobotModel};
use packwright_compiler::{Error, Failed, Loc, load, resolve, validate, workspace};
use packwright_draw::{
    Event, EventKind, Mark, Picture, Place, Product, ProductState, Sample, ToolPath, UR10_REACH,
};
use packwright_interface::outcome::{Report, Stage};
use packwright_kinematics::Arm;
use packwright_pipeline::episode::scene_of;
use packwright_pipeline::reach::RobotWorkspace;
use packwright_recording::Cycle;

/// What a picture shows: a cell (by its index in the model), an
/// inventory's products in their cell, or a setup (an order's or a
/// scenario's products, with the assignment).
pub enum Subject {
    Cell(usize),
    Inventory(usize),
    Setup {
        title: String,
        order: Option<usize>,
        setup: Setup,
    },
}

impl Subject {
    /// Order `o` of `model` as written: every product at its inventory
    /// position, none packed by a worker or missing.
    pub fn order(model: &Model, o: usize) -> Subject {
        let order = &model.orders[o];
        let inv = &model.inventories[order.inventory];
        Subject::Setup {
            title: format!("order {}", order.name),
            order: Some(o),
            setup: Setup {
                inventory: order.inventory,
                assignment: order.assignment.iter().map(|a| (a.entry, a.slot)).collect(),
                human_packed: Vec::new(),
                missing: Vec::new(),
                positions: inv.entries.iter().map(|e| e.at).collect(),
            },
        }
    }
}

pub fn run(args: &DrawArgs) -> anyhow::Result<Exit> {
    let loaded = load::load(&FsLoader, &args.files);
    if !loaded.errors.is_empty() {
        return Ok(refuse(loaded.sources, loaded.errors));
    }
    let (model, errors) = resolve::resolve(&FsLoader, &loaded.sources, &loaded.files);
    if !errors.is_empty() {
        return Ok(refuse(loaded.sources, errors));
    }
    // Geometry and reach are drawn, not refused: the picture shows them.
    let mut diagnostics = validate::validate(&model);
    if diagnostics.is_empty() {
        let warnings;
        (diagnostics, warnings) = workspace::check(&model, &RobotWorkspace::new());
        super::report_warnings(&loaded.sources, &warnings, false);
    }
    // What `check` finds in the generators (E045-E048) too, listed under
    // the picture, so that draw's exit code is check's. A scenario's
    // picture expands them below.
    if diagnostics.is_empty()
        && args.scenario.is_none()
        && let Err(errors) = expand::expand(&model)
    {
        diagnostics = errors;
    }
    let subject = if let Some(name) = &args.scenario {
        if !diagnostics.is_empty() {
            errln!("a scenario is drawn only from files without diagnostics:");
            return Ok(refuse(loaded.sources, diagnostics));
        }
        let expanded = match expand::expand(&model) {
            Ok(x) => x,
            Err(errors) => return Ok(refuse(loaded.sources, errors)),
        };
        let found = expanded.suites.iter().find_map(|suite| {
            let case = suite.cases.iter().find(|c| &c.name == name)?;
            Some((suite.order, case.setup.clone()))
        });
        let Some((order, setup)) = found else {
            bail!(
                "no scenario `{name}`; {}",
                packwright_pipeline::episode::scenario_hint(&expanded, name)
            );
        };
        Subject::Setup {
            title: format!("scenario {name}"),
            order,
            setup,
        }
    } else if let Some(name) = &args.order {
        let o = index_of(
            model.orders.iter().map(|o| &o.name),
            name,
            ("order", "orders"),
        )?;
        Subject::order(&model, o)
    } else if let Some(name) = &args.inventory {
        let i = index_of(
            model.inventories.iter().map(|i| &i.name),
            name,
            ("inventory", "inventories"),
        )?;
        Subject::Inventory(i)
    } else if let Some(name) = &args.cell {
        let c = index_of(model.cells.iter().map(|c| &c.name), name, ("cell", "cells"))?;
        Subject::Cell(c)
    } else if model.cells.len() == 1 {
        Subject::Cell(0)
    } else if model.cells.is_empty() {
        bail!("the files define no cell to draw");
    } else {
        bail!(
            "the files define {} cells: name one with --cell NAME ({})",
            model.cells.len(),
            names(model.cells.iter().map(|c| &c.name))
        );
    };
    let picture = picture_of(&model, &subject, &diagnostics);
    if let Subject::Cell(c) = subject {
        let invs: Vec<&String> = model
            .inventories
            .iter()
            .filter(|i| i.cell == c)
            .map(|i| &i.name)
            .collect();
        match invs.as_slice() {
            [] => {}
            [one] => errln!("note: --inventory {one} draws its products too"),
            _ => errln!(
                "note: --inventory NAME draws the products of one of {}",
                names(invs.into_iter())
            ),
        }
    }
    let svg = packwright_draw::picture(&picture)?;
    match &args.output {
        Some(path) => {
            write_file_atomically(path, svg.as_bytes())?;
            outln!("{}", path.display());
        }
        None => out!("{svg}"),
    }
    if diagnostics.is_empty() {
        return Ok(Exit::Success);
    }
    let failed = failed(loaded.sources, diagnostics);
    err!("{}", failed.render());
    let drawn = picture
        .marks
        .iter()
        .filter(|m| m.place != Place::Cell)
        .count();
    // Diagnostics about what the picture does not show (another cell, an
    // order not drawn) are neither drawn nor listed: say how many.
    let elsewhere = failed.errors.len().saturating_sub(picture.marks.len());
    errln!(
        "\n{} diagnostic{} ({drawn} drawn where {}, {} more listed under the picture{})",
        failed.errors.len(),
        if failed.errors.len() == 1 { "" } else { "s" },
        if drawn == 1 { "it is" } else { "they are" },
        picture.marks.len() - drawn,
        if elsewhere > 0 {
            format!(", {elsewhere} about what this picture does not show")
        } else {
            String::new()
        }
    );
    Ok(Exit::Diagnostics)
}

/// Where `name` stands among `all`, the names of the `what`s
/// (singular, plural), or an error that lists them.
fn index_of<'a>(
    all: impl Iterator<Item = &'a String> + Clone,
    name: &str,
    (what, plural): (&str, &str),
) -> anyhow::Result<usize> {
    match all.clone().position(|n| n == name) {
        Some(i) => Ok(i),
        None => bail!("no {what} `{name}`; known {plural}: {}", names(all)),
    }
}

fn names<'a>(names: impl Iterator<Item = &'a String>) -> String {
    names.map(String::as_str).collect::<Vec<_>>().join(", ")
}

fn failed(sources: packwright_compiler::SourceMap, mut errors: Vec<Error>) -> Failed {
    errors.sort_by_key(|e| e.at());
    Failed { sources, errors }
}

fn refuse(sources: packwright_compiler::SourceMap, errors: Vec<Error>) -> Exit {
    let exit = super::report_failure(&failed(sources, errors), false);
    errln!("no picture written: a picture is drawn from files that parse and whose names resolve");
    exit
}

/// The picture of `subject`, with the diagnostics that belong to it
/// (`model` resolved: its indices hold; geometry need not be valid).
pub fn picture_of(model: &Model, subject: &Subject, diagnostics: &[Error]) -> Picture {
    let (cell, inventory, order, setup, title) = match subject {
        Subject::Cell(c) => (*c, None, None, None, String::new()),
        Subject::Inventory(i) => (
            model.inventories[*i].cell,
            Some(*i),
            None,
            None,
            format!("inventory {}", model.inventories[*i].name),
        ),
        Subject::Setup {
            title,
            order,
            setup,
        } => (
            model.inventories[setup.inventory].cell,
            Some(setup.inventory),
            *order,
            Some(setup),
            title.clone(),
        ),
    };
    let c = &model.cells[cell];
    let title = if title.is_empty() {
        format!("cell {}", c.name)
    } else {
        format!("{title} (cell {})", c.name)
    };
    let mut picture = Picture::new(title, scene_of(&cell_record(c)));
    if c.robot == RobotModel::Ur10 {
        picture.reach = Some(UR10_REACH);
    }
    if let Some(i) = inventory {
        let inv = &model.inventories[i];
        for (e, entry) in inv.entries.iter().enumerate() {
            let p = &model.products[entry.product];
            let at = setup.map_or(entry.at, |s| {
                s.positions.get(e).copied().unwrap_or(entry.at)
            });
            let slot = setup.and_then(|s| s.slot_of(e));
            let (centre, state) = match (setup, slot) {
                (Some(s), _) if s.missing.contains(&e) => {
                    ([at[0], at[1], p.size[2] / 2.0], ProductState::Missing)
                }
                (Some(s), Some(slot)) if s.human_packed.contains(&e) => {
                    let goal = c.slots[slot].at;
                    (
                        [goal[0], goal[1], p.size[2] / 2.0],
                        ProductState::WorkerPacked,
                    )
                }
                _ => ([at[0], at[1], p.size[2] / 2.0], ProductState::Waiting),
            };
            picture.products.push(Product {
                name: p.name.clone(),
                size: p.size,
                centre,
                state,
            });
        }
    }
    if let Some(s) = setup {
        picture.assignment = s.assignment.clone();
    }
    picture.marks = diagnostics
        .iter()
        .filter_map(|e| mark(model, cell, inventory, order, e))
        .collect();
    picture
}

fn within(inner: Loc, outer: Loc) -> bool {
    inner.file == outer.file
        && inner.span.start >= outer.span.start
        && inner.span.end <= outer.span.end
}

/// Where diagnostic `e` is drawn, if it belongs to the picture: on the
/// slot, box, product or assignment it is reported at; an unreachable
/// pose at its tool tip; listed under the picture only when it is reported
/// at the drawn cell, inventory or order itself; else not in the picture
/// (stderr has every diagnostic).
fn mark(
    model: &Model,
    cell: usize,
    inventory: Option<usize>,
    order: Option<usize>,
    e: &Error,
) -> Option<Mark> {
    let at = e.at()?;
    let c = &model.cells[cell];
    let inv = inventory.map(|i| &model.inventories[i]);
    let ord = order.map(|o| &model.orders[o]);
    let mut place = None;
    if let Some(s) = c.slots.iter().position(|s| within(at, s.loc)) {
        place = Some(Place::Slot(s));
    } else if let Some(b) = c.boxes.iter().position(|b| within(at, b.loc)) {
        place = Some(Place::Box(b));
    } else if let Some(p) = inv.and_then(|inv| inv.entries.iter().position(|x| within(at, x.loc))) {
        place = Some(Place::Product(p));
    } else if let Some(a) = ord.and_then(|o| o.assignment.iter().find(|a| within(at, a.loc))) {
        place = Some(Place::Slot(a.slot));
    }
    let ours = place.is_some()
        || within(at, c.loc)
        || inv.is_some_and(|i| within(at, i.loc))
        || ord.is_some_and(|o| within(at, o.loc));
    if let Error::Unreachable { tip, .. } = e
        && ours
    {
        place = Some(Place::Point(*tip));
    }
    let place = match place {
        Some(p) => p,
        None if ours => Place::Cell,
        None => return None,
    };
    Some(Mark {
        place,
        code: e.code().to_owned(),
        message: e.to_string(),
    })
}

/// The picture of a scenario or an order (`setup`) as `execute` ran it:
/// the cell and its products at their start, the assignment, the tool
/// path of `cycles` (journalled by `JournalWorld`: forward kinematics of
/// the commanded joints, coloured
/// by the suction's stage), each fallback at the pick or release of its
/// product and stage, and the first failure where the arm stopped.
pub fn executed_picture(
    model: &Model,
    name: &str,
    setup: &Setup,
    arm: &Arm,
    cycles: &[Cycle],
    report: &Report,
) -> Picture {
    let subject = Subject::Setup {
        title: format!("{name}, planner {}", report.planner),
        order: None,
        setup: setup.clone(),
    };
    let mut picture = picture_of(model, &subject, &[]);
    let b = picture.cell.base;
    let base = Isometry3::translation(b[0], b[1], b[2]);
    let suction = picture.cell.suction;
    let samples: Vec<Sample> = cycles
        .iter()
        .map(|c| {
            let tip = arm.tool_tip(&base, &c.commanded, suction);
            Sample {
                tip: [tip.x, tip.y, tip.z],
                suction: c.suction,
                speed: c.speed,
            }
        })
        .collect();
    let mut path = ToolPath::from_samples(&samples, &report.subgoals);
    // Each pick belongs to the product nearest the cup; its release
    // follows it.
    let mut handled: Vec<(String, [f64; 3], Option<[f64; 3]>)> = Vec::new();
    for e in &path.events {
        match e.kind {
            EventKind::Pick => {
                let nearest = picture
                    .products
                    .iter()
                    .filter(|p| p.state == ProductState::Waiting)
                    .min_by(|a, b| flat(a.centre, e.at).total_cmp(&flat(b.centre, e.at)));
                if let Some(p) = nearest {
                    handled.push((p.name.clone(), e.at, None));
                }
            }
            EventKind::Release => {
                if let Some(last) = handled.last_mut() {
                    last.2 = Some(e.at);
                }
            }
            _ => {}
        }
    }
    for f in &report.fallbacks {
        let at = handled
            .iter()
            .find(|(p, _, _)| *p == f.product)
            .and_then(|(_, pick, release)| match f.stage {
                Stage::Picking => Some(*pick),
                Stage::Placing => *release,
            })
            .or(path.end());
        if let Some(at) = at {
            path.events.push(Event {
                at,
                kind: EventKind::Fallback(f.to_string()),
            });
        }
    }
    if let (Some(why), Some(at)) = (report.first_problem(), path.end()) {
        path.events.push(Event {
            at,
            kind: EventKind::Failure(why),
        });
    }
    picture.path = Some(path);
    picture
}

/// Distance on the table (x, y).
fn flat(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// `execute --svg FILE`: the executed picture written atomically, its path
/// on stderr (stdout keeps the report).
pub fn write_executed_svg(
    path: &std::path::Path,
    model: &Model,
    name: &str,
    setup: &Setup,
    arm: &Arm,
    cycles: &[Cycle],
    report: &Report,
) -> anyhow::Result<()> {
    let picture = executed_picture(model, name, setup, arm, cycles, report);
    write_file_atomically(path, packwright_draw::picture(&picture)?.as_bytes())?;
    errln!("wrote {}", path.display());
    Ok(())
}
