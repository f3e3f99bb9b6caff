//! From pest's parse tree to the typed AST, collecting every syntax error.

use crate::ast::*;
use crate::error::{MAX_BARE_METRES, MAX_SYNTAX_ERRORS, SyntaxError};
use crate::place::{Place, statement_word};
use crate::span::Span;
use crate::suggest::closest;
use pest::Parser;
use pest::iterators::Pair;

#[derive(pest_derive::Parser)]
#[grammar = "pack.pest"]
struct PackParser;

/// Parses one `.pack` text. On failure returns every syntax error found,
/// sorted by position.
pub fn parse(src: &str) -> Result<File, Vec<SyntaxError>> {
    let mut b = Builder { errors: Vec::new() };
    let file = match PackParser::parse(Rule::file, src) {
        Ok(mut pairs) => match pairs.next() {
            Some(pair) => b.file(pair),
            None => File { items: Vec::new() },
        },
        Err(e) => {
            b.errors.push(from_pest(src, e, 0, Place::TopLevel));
            File { items: Vec::new() }
        }
    };
    if b.errors.is_empty() {
        Ok(file)
    } else {
        b.errors.sort_by_key(|e| e.span());
        Err(b.errors)
    }
}

type P<'i> = Pair<'i, Rule>;

/// The span of a pair without the blanks and comments that pest's implicit
/// whitespace may have consumed after its last token: it ends where its
/// last leaf token ends.
fn span(p: &P) -> Span {
    let start = p.as_span().start();
    let end = p
        .clone()
        .into_inner()
        .flatten()
        .filter(|k| k.clone().into_inner().next().is_none())
        .map(|k| k.as_span().end())
        .max()
        .unwrap_or(p.as_span().end());
    Span::new(start, end)
}

fn is_punct(rule: Rule) -> bool {
    matches!(
        rule,
        Rule::lparen
            | Rule::rparen
            | Rule::comma
            | Rule::lbrace
            | Rule::rbrace
            | Rule::quote
            | Rule::arrow
    )
}

/// The children of a pair, without punctuation.
fn kids<'i>(p: P<'i>) -> impl Iterator<Item = P<'i>> {
    p.into_inner().filter(|k| !is_punct(k.as_rule()))
}

/// Readable name of what a rule matches, for "expected ..." messages.
fn describe(rule: Rule) -> Option<&'static str> {
    Some(match rule {
        Rule::name | Rule::names => "a name",
        Rule::number | Rule::quantity => "a number such as `50 mm`",
        Rule::unit => "a unit",
        Rule::point | Rule::lparen => "a point such as `(0.5, -0.2)`",
        Rule::comma => "`,`",
        Rule::rparen => "`)`",
        Rule::lbrace => "`{`",
        Rule::rbrace => "`}`",
        Rule::quote | Rule::string => "a quoted string",
        Rule::arrow => "`->`",
        Rule::seq_mode => "`ascending`, `descending`, `listed` or `random`",
        Rule::EOI => "the end of the line",
        Rule::kw_use => "`use`",
        Rule::kw_cell => "`cell`",
        Rule::kw_product => "`product`",
        Rule::kw_inventory => "`inventory`",
        Rule::kw_order => "`order`",
        Rule::kw_demo => "`demo`",
        Rule::kw_demos => "`demos`",
        Rule::kw_scenario => "`scenario`",
        Rule::kw_scenarios => "`scenarios`",
        Rule::kw_for => "`for`",
        Rule::kw_robot => "`robot`",
        Rule::kw_ur10 => "`ur10`",
        Rule::kw_urdf => "`urdf`",
        Rule::kw_base => "`base`",
        Rule::kw_suction => "`suction`",
        Rule::kw_pending => "`pending`",
        Rule::kw_to => "`to`",
        Rule::kw_box => "`box`",
        Rule::kw_size => "`size`",
        Rule::kw_slot => "`slot`",
        Rule::kw_lift => "`lift`",
        Rule::kw_speed => "`speed`",
        Rule::kw_settle => "`settle`",
        Rule::kw_descent => "`descent`",
        Rule::kw_acceleration => "`acceleration`",
        Rule::kw_jerk => "`jerk`",
        Rule::kw_after => "`after`",
        Rule::settle_event => "`grip` or `release`",
        Rule::kw_cube => "`cube`",
        Rule::kw_mass => "`mass`",
        Rule::kw_customer => "`customer`",
        Rule::kw_batch => "`batch`",
        Rule::kw_sequence => "`sequence`",
        Rule::kw_at => "`at`",
        Rule::kw_choose => "`choose`",
        Rule::kw_of => "`of`",
        Rule::kw_into => "`into`",
        Rule::kw_keep => "`keep`",
        Rule::kw_jitter => "`jitter`",
        Rule::kw_repeat => "`repeat`",
        Rule::kw_seed => "`seed`",
        Rule::kw_human => "`human`",
        Rule::kw_packed => "`packed`",
        Rule::kw_packs => "`packs`",
        Rule::kw_missing => "`missing`",
        Rule::kw_count => "`count`",
        _ => return None,
    })
}

/// Turns a pest error on `src[offset..]` into a syntax error located in `src`.
/// A number in scientific notation (`5e-2`, `1E3`) that the parse broke
/// at its exponent (`5` read with the unit `e`, then `-2` unexpected):
/// the whole literal's span, the literal and the number written plainly
/// (`0.05`), when the text at `at` is the exponent of one.
fn scientific(src: &str, at: Span) -> Option<(Span, String, Option<String>)> {
    let exponent = src.get(at.start as usize..at.end as usize)?;
    let before = src.get(..at.start as usize)?;
    let mantissa_end = before.strip_suffix(['e', 'E'])?;
    let mantissa_start = mantissa_end
        .char_indices()
        .rev()
        .take_while(|(_, c)| c.is_ascii_digit() || *c == '.' || *c == '-')
        .last()
        .map(|(i, _)| i)?;
    let mantissa = &mantissa_end[mantissa_start..];
    if !mantissa.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '.')
        || !exponent
            .trim_start_matches(['-', '+'])
            .chars()
            .all(|c| c.is_ascii_digit())
    {
        return None;
    }
    let written = format!("{mantissa}{}{exponent}", &before[mantissa_end.len()..]);
    let value: f64 = written.parse().ok()?;
    let span = Span::new(mantissa_start, at.end as usize);
    // Written plainly only where that is a number a cell could use: not
    // 309 digits (`1e308`), infinity (`1e400`) or a zero the exponent
    // made (`1e-400`).
    let plain = format!("{value}");
    let mantissa_zero = mantissa
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.');
    let usable =
        value.is_finite() && plain.len() <= PLAIN_DIGITS && (value != 0.0 || mantissa_zero);
    Some((span, written, usable.then_some(plain)))
}

/// The longest number [`scientific`] writes out plainly.
const PLAIN_DIGITS: usize = 16;

fn from_pest(src: &str, e: pest::error::Error<Rule>, offset: usize, context: Place) -> SyntaxError {
    let pos = offset
        + match e.location {
            pest::error::InputLocation::Pos(p) => p,
            pest::error::InputLocation::Span((s, _)) => s,
        };
    let positives = match e.variant {
        pest::error::ErrorVariant::ParsingError { positives, .. } => positives,
        pest::error::ErrorVariant::CustomError { .. } => Vec::new(),
    };
    let mut expected: Vec<&'static str> = Vec::new();
    for d in positives.iter().filter_map(|r| describe(*r)) {
        if !expected.contains(&d) {
            expected.push(d);
        }
    }
    if expected.len() > 1 {
        expected.retain(|d| *d != "a unit");
    }
    // Every word quoted in the descriptions (a sequence mode's four, a
    // keyword's one), not examples such as `50 mm`.
    let keywords: Vec<&str> = positives
        .iter()
        .filter_map(|r| describe(*r))
        .flat_map(|d| d.split('`').skip(1).step_by(2))
        .filter(|w| !w.is_empty() && !w.contains(char::is_whitespace))
        .collect();
    let (found, found_span) = token_at(src, pos);
    if expected == ["a quoted string"] && found == "the end of the line" {
        expected = vec!["a closing `\"` (strings end on the line they start)"];
    }
    if let Some((span, written, plain)) = scientific(src, found_span) {
        return SyntaxError::Exponent {
            span,
            written,
            plain,
        };
    }
    let suggestion = if found.starts_with('`') {
        closest(found.trim_matches('`'), keywords.iter().copied()).map(str::to_owned)
    } else {
        None
    };
    SyntaxError::Unexpected {
        span: found_span,
        expected: join_or(&expected),
        found,
        context,
        suggestion,
        statement: statement_word(src, pos).map(str::to_owned),
        invisible: src
            .get(pos..)
            .and_then(|rest| rest.chars().next())
            .is_some_and(crate::visible::is_invisible),
    }
}

fn join_or(items: &[&str]) -> String {
    match items {
        [] => "something else".into(),
        [one] => (*one).into(),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
    }
}

/// What stands at `pos`: a word, one character, or the end of a line/file.
fn token_at(src: &str, pos: usize) -> (String, Span) {
    let rest = src.get(pos..).unwrap_or("");
    let Some(c) = rest.chars().next() else {
        return ("end of file".into(), Span::new(src.len(), src.len()));
    };
    if c == '\n' || c == '\r' {
        return ("the end of the line".into(), Span::new(pos, pos));
    }
    let is_word = |c: char| c.is_alphanumeric() || c == '_' || c == '.' || c == '-';
    if is_word(c) {
        let len: usize = rest
            .chars()
            .take_while(|&c| is_word(c))
            .map(char::len_utf8)
            .sum();
        return (format!("`{}`", &rest[..len]), Span::new(pos, pos + len));
    }
    (crate::visible::named(c), Span::new(pos, pos + c.len_utf8()))
}

struct Builder {
    errors: Vec<SyntaxError>,
}

impl Builder {
    fn file(&mut self, pair: P) -> File {
        let src = pair.as_str();
        let mut items = Vec::new();
        // After a bad item that opens a block, the block's lines are bad
        // items too: skip them, up to the line that closes it.
        let mut skipping = false;
        for p in pair.into_inner() {
            if self.errors.len() >= MAX_SYNTAX_ERRORS {
                let at = p.as_span().start();
                self.errors.push(SyntaxError::TooMany {
                    span: Span::new(at, at),
                });
                break;
            }
            let item = match p.as_rule() {
                Rule::use_item => self.use_item(p),
                Rule::cell => self.cell(src, p),
                Rule::product => self.product(p),
                Rule::inventory => self.inventory(src, p),
                Rule::order => self.order(src, p),
                Rule::demo => self.demo(src, p),
                Rule::demos => self.demos(src, p),
                Rule::scenario => self.scenario(src, p),
                Rule::scenarios => self.scenarios(src, p),
                Rule::bad_item => {
                    let text = p.as_str();
                    if skipping {
                        skipping = !text.trim_start().starts_with('}');
                    } else {
                        self.bad_item(src, &p);
                        skipping = text.matches('{').count() > text.matches('}').count();
                    }
                    continue;
                }
                _ => continue,
            };
            skipping = false;
            items.push(item);
        }
        File { items }
    }

    /// Reports a line that is not an item. A good block header whose block
    /// is never closed is reported at its `{`.
    fn bad_item(&mut self, src: &str, p: &P) {
        let text = p.as_str();
        let start = p.as_span().start();
        // Where the parser was, by the item's first word: a product line
        // missing its shape is "in a product", not "at the top level".
        let context = Place::of_item(text.split_whitespace().next());
        let unclosed = text.matches('{').count() > text.matches('}').count();
        match PackParser::parse(Rule::item_only, text) {
            Err(e) => {
                let at_end = match e.location {
                    pest::error::InputLocation::Pos(pos) => {
                        text[pos.min(text.len())..].trim().is_empty()
                    }
                    pest::error::InputLocation::Span((s, _)) => {
                        text[s.min(text.len())..].trim().is_empty()
                    }
                };
                match text.rfind('{') {
                    Some(brace) if unclosed && at_end => self.errors.push(SyntaxError::Unclosed {
                        span: Span::new(start + brace, start + brace + 1),
                    }),
                    _ => self.errors.push(from_pest(src, e, start, context)),
                }
            }
            Ok(_) => self.reparse(src, Rule::item_only, p, context),
        }
    }

    /// Re-parses a recovered fragment with the rule expected there, to say
    /// precisely what is wrong with it.
    fn reparse(&mut self, src: &str, rule: Rule, p: &P, context: Place) {
        let start = p.as_span().start();
        match PackParser::parse(rule, p.as_str()) {
            Err(e) => self.errors.push(from_pest(src, e, start, context)),
            Ok(_) => {
                let end = p.as_span().end();
                let (found, span) = token_at(src, end);
                self.errors.push(SyntaxError::Unexpected {
                    span,
                    expected: "the end of the line".into(),
                    found,
                    context,
                    suggestion: None,
                    statement: statement_word(src, start).map(str::to_owned),
                    invisible: false,
                });
            }
        }
    }

    /// Splits a block into its name, its `for` target (if any) and its
    /// statement pairs; bad statements are reported and dropped.
    fn block<'i>(
        &mut self,
        src: &str,
        p: P<'i>,
        only: Rule,
        context: Place,
    ) -> (Name, Option<Name>, Vec<P<'i>>) {
        let mut names = Vec::new();
        let mut stmts = Vec::new();
        for k in kids(p) {
            match k.as_rule() {
                Rule::name => names.push(name(&k)),
                Rule::bad_stmt => self.reparse(src, only, &k, context),
                r if describe(r).is_some_and(|d| d.starts_with('`')) => {}
                _ => stmts.push(k),
            }
        }
        let mut names = names.into_iter();
        let own = names.next().unwrap_or_else(|| Name {
            text: String::new(),
            span: Span::default(),
        });
        (own, names.next(), stmts)
    }

    fn use_item(&mut self, p: P) -> Item {
        let s = span(&p);
        let path = kids(p)
            .find(|k| k.as_rule() == Rule::string)
            .map(|k| string(&k));
        Item::Use(Use {
            path: path.unwrap_or(Str {
                value: String::new(),
                span: s,
            }),
            span: s,
        })
    }

    fn cell(&mut self, src: &str, p: P) -> Item {
        let s = span(&p);
        let (name_, _, raw) = self.block(src, p, Rule::cell_stmt_only, Place::Cell);
        let mut stmts = Vec::new();
        for st in raw {
            let ss = span(&st);
            let rule = st.as_rule();
            let mut k: Vec<P> = kids(st).collect();
            let kind = match rule {
                Rule::robot_stmt => {
                    let robot = match k.iter().find(|x| x.as_rule() == Rule::string) {
                        Some(path) => Robot::Urdf(string(path)),
                        None => Robot::Ur10,
                    };
                    CellStmt::Robot(robot)
                }
                Rule::base_stmt => CellStmt::Base(self.point(k.remove(1))),
                Rule::suction_stmt => CellStmt::Suction(self.length(k.remove(1))),
                Rule::lift_stmt => CellStmt::Lift(self.length(k.remove(1))),
                Rule::speed_stmt => CellStmt::Speed(
                    self.share(
                        k.remove(1),
                        "`%` (a share of the arm's top joint speeds), or no unit for a fraction (`speed 0.5`)",
                    ),
                ),
                Rule::descent_stmt => CellStmt::Descent(self.share(
                    k.remove(1),
                    "`%`, or no unit for a fraction (`descent 0.25`)",
                )),
                Rule::acceleration_stmt => {
                    CellStmt::Acceleration(self.joint_values(k.remove(1), "an acceleration"))
                }
                Rule::jerk_stmt => CellStmt::Jerk(self.joint_values(k.remove(1), "a jerk")),
                Rule::settle_stmt => {
                    let after = if k.get(3).is_some_and(|e| e.as_str() == "grip") {
                        SettleAfter::Grip
                    } else {
                        SettleAfter::Release
                    };
                    CellStmt::Settle {
                        time: self.time(k.remove(1)),
                        after,
                    }
                }
                Rule::pending_stmt => {
                    let to = self.point(k.remove(3));
                    let from = self.point(k.remove(1));
                    CellStmt::Pending(from, to)
                }
                Rule::box_stmt => {
                    let size = self.size(k.remove(4));
                    let at = self.point(k.remove(2));
                    CellStmt::Box {
                        name: name(&k[1]),
                        at,
                        size,
                    }
                }
                Rule::slot_stmt => {
                    let at = self.point(k.remove(2));
                    CellStmt::Slot {
                        name: name(&k[1]),
                        at,
                    }
                }
                _ => continue,
            };
            stmts.push(Stmt { kind, span: ss });
        }
        Item::Cell(Cell {
            name: name_,
            stmts,
            span: s,
        })
    }

    fn product(&mut self, p: P) -> Item {
        let s = span(&p);
        let mut product_name = None;
        let mut shape = None;
        let mut mass = None;
        for k in kids(p) {
            match k.as_rule() {
                Rule::name => product_name = Some(name(&k)),
                Rule::cube_shape => {
                    if let Some(q) = kids(k).nth(1) {
                        shape = Some(Shape::Cube(self.length(q)));
                    }
                }
                Rule::box_shape => {
                    if let Some(q) = kids(k).nth(1) {
                        shape = Some(Shape::Box(self.size(q)));
                    }
                }
                Rule::mass_clause => {
                    if let Some(q) = kids(k).nth(1) {
                        mass = Some(self.mass(q));
                    }
                }
                _ => {}
            }
        }
        Item::Product(Product {
            name: product_name.unwrap_or(Name {
                text: String::new(),
                span: s,
            }),
            shape: shape.unwrap_or(Shape::Cube(zero_length(s))),
            mass,
            span: s,
        })
    }

    fn inventory(&mut self, src: &str, p: P) -> Item {
        let s = span(&p);
        let (name_, cell, raw) = self.block(src, p, Rule::inventory_stmt_only, Place::Inventory);
        let mut entries = Vec::new();
        for st in raw {
            let ss = span(&st);
            let mut k: Vec<P> = kids(st).collect();
            if k.len() < 2 {
                continue;
            }
            let at = self.point(k.remove(1));
            entries.push(Stmt {
                kind: Entry {
                    product: name(&k[0]),
                    at,
                },
                span: ss,
            });
        }
        Item::Inventory(Inventory {
            name: name_,
            cell: cell.unwrap_or_else(|| missing_name(s)),
            entries,
            span: s,
        })
    }

    fn order(&mut self, src: &str, p: P) -> Item {
        let s = span(&p);
        let (name_, inv, raw) = self.block(src, p, Rule::order_stmt_only, Place::Order);
        let mut stmts = Vec::new();
        for st in raw {
            let ss = span(&st);
            let rule = st.as_rule();
            let mut k: Vec<P> = kids(st).collect();
            let kind = match rule {
                Rule::customer_stmt => OrderStmt::Customer(string(&k[1])),
                Rule::batch_stmt => OrderStmt::Batch(self.count(k.remove(1), "`batch`")),
                Rule::assign_stmt => OrderStmt::Assign {
                    product: name(&k[0]),
                    slot: name(&k[1]),
                },
                _ => continue,
            };
            stmts.push(Stmt { kind, span: ss });
        }
        Item::Order(Order {
            name: name_,
            inventory: inv.unwrap_or_else(|| missing_name(s)),
            stmts,
            span: s,
        })
    }

    fn demo(&mut self, src: &str, p: P) -> Item {
        let s = span(&p);
        let (name_, order, raw) = self.block(src, p, Rule::demo_stmt_only, Place::Demo);
        let mut stmts = Vec::new();
        for st in raw {
            let ss = span(&st);
            let rule = st.as_rule();
            let kind = match rule {
                Rule::sequence_list => DemoStmt::Sequence(names_of(st)),
                Rule::at_stmt => {
                    let (product, at) = self.at(st);
                    DemoStmt::At { product, at }
                }
                _ => continue,
            };
            stmts.push(Stmt { kind, span: ss });
        }
        Item::Demo(Demo {
            name: name_,
            order: order.unwrap_or_else(|| missing_name(s)),
            stmts,
            span: s,
        })
    }

    fn demos(&mut self, src: &str, p: P) -> Item {
        let s = span(&p);
        let (name_, inv, raw) = self.block(src, p, Rule::demos_stmt_only, Place::Demos);
        let mut stmts = Vec::new();
        for st in raw {
            let ss = span(&st);
            let rule = st.as_rule();
            let kind = match rule {
                Rule::choose_stmt => DemosStmt::Choose(self.choose(st)),
                Rule::keep_stmt => DemosStmt::Keep(self.fraction(last(st), "`keep`")),
                Rule::jitter_stmt => DemosStmt::Jitter(self.length(last(st))),
                Rule::sequence_mode => DemosStmt::Sequence(seq_mode(&last(st))),
                Rule::repeat_stmt => DemosStmt::Repeat(self.count(last(st), "`repeat`")),
                Rule::seed_stmt => DemosStmt::Seed(self.count(last(st), "`seed`")),
                Rule::human_packs_stmt => DemosStmt::HumanPacks(self.range(st)),
                Rule::missing_range_stmt => DemosStmt::Missing(self.range(st)),
                _ => continue,
            };
            stmts.push(Stmt { kind, span: ss });
        }
        Item::Demos(Demos {
            name: name_,
            inventory: inv.unwrap_or_else(|| missing_name(s)),
            stmts,
            span: s,
        })
    }

    fn scenario(&mut self, src: &str, p: P) -> Item {
        let s = span(&p);
        let (name_, order, raw) = self.block(src, p, Rule::scenario_stmt_only, Place::Scenario);
        let mut stmts = Vec::new();
        for st in raw {
            let ss = span(&st);
            let rule = st.as_rule();
            let kind = match rule {
                Rule::human_packed_stmt => ScenarioStmt::HumanPacked(names_of(st)),
                Rule::missing_list_stmt => ScenarioStmt::Missing(names_of(st)),
                Rule::jitter_stmt => ScenarioStmt::Jitter(self.length(last(st))),
                Rule::seed_stmt => ScenarioStmt::Seed(self.count(last(st), "`seed`")),
                Rule::at_stmt => {
                    let (product, at) = self.at(st);
                    ScenarioStmt::At { product, at }
                }
                _ => continue,
            };
            stmts.push(Stmt { kind, span: ss });
        }
        Item::Scenario(Scenario {
            name: name_,
            order: order.unwrap_or_else(|| missing_name(s)),
            stmts,
            span: s,
        })
    }

    fn scenarios(&mut self, src: &str, p: P) -> Item {
        let s = span(&p);
        let (name_, inv, raw) = self.block(src, p, Rule::scenarios_stmt_only, Place::Scenarios);
        let mut stmts = Vec::new();
        for st in raw {
            let ss = span(&st);
            let rule = st.as_rule();
            let kind = match rule {
                Rule::choose_stmt => ScenariosStmt::Choose(self.choose(st)),
                Rule::human_packs_stmt => ScenariosStmt::HumanPacks(self.range(st)),
                Rule::missing_range_stmt => ScenariosStmt::Missing(self.range(st)),
                Rule::jitter_stmt => ScenariosStmt::Jitter(self.length(last(st))),
                Rule::count_stmt => ScenariosStmt::Count(self.count(last(st), "`count`")),
                Rule::seed_stmt => ScenariosStmt::Seed(self.count(last(st), "`seed`")),
                _ => continue,
            };
            stmts.push(Stmt { kind, span: ss });
        }
        Item::Scenarios(Scenarios {
            name: name_,
            inventory: inv.unwrap_or_else(|| missing_name(s)),
            stmts,
            span: s,
        })
    }

    // ---- pieces ---------------------------------------------------------

    fn choose(&mut self, p: P) -> Choose {
        let s = span(&p);
        let mut n = None;
        let mut lists = Vec::new();
        for k in kids(p) {
            match k.as_rule() {
                Rule::quantity => n = Some(self.count(k, "`choose`")),
                Rule::names => lists.push(names_of(k)),
                _ => {}
            }
        }
        let mut lists = lists.into_iter();
        Choose {
            n: n.unwrap_or(Count { value: 0, span: s }),
            products: lists.next().unwrap_or_default(),
            slots: lists.next().unwrap_or_default(),
        }
    }

    fn range(&mut self, p: P) -> Range {
        let s = span(&p);
        let qs: Vec<P> = kids(p).filter(|k| k.as_rule() == Rule::quantity).collect();
        let mut bounds = qs.into_iter().map(|q| self.count(q, "a range bound"));
        let low = bounds.next().unwrap_or(Count { value: 0, span: s });
        let high = bounds.next().unwrap_or(Count { value: 0, span: s });
        Range { low, high, span: s }
    }

    fn at(&mut self, p: P) -> (Name, Point) {
        let s = span(&p);
        let mut product = missing_name(s);
        let mut at = None;
        for k in kids(p) {
            match k.as_rule() {
                Rule::name => product = name(&k),
                Rule::point => at = Some(self.point(k)),
                _ => {}
            }
        }
        (product, at.unwrap_or_else(|| zero_point(s)))
    }

    /// A position: coordinates may be any size.
    fn point(&mut self, p: P) -> Point {
        self.point_with(p, false)
    }

    /// A size `(w, d, h)`: a bare number above a few metres is taken for a
    /// forgotten unit.
    fn size(&mut self, p: P) -> Point {
        self.point_with(p, true)
    }

    fn point_with(&mut self, p: P, is_size: bool) -> Point {
        let s = span(&p);
        let mut qs = kids(p)
            .map(|q| self.length_with(q, is_size))
            .collect::<Vec<_>>()
            .into_iter();
        let x = qs.next().unwrap_or_else(|| zero_length(s));
        let y = qs.next().unwrap_or_else(|| zero_length(s));
        Point {
            x,
            y,
            z: qs.next(),
            span: s,
        }
    }

    /// Splits a `quantity` into its number (text, value) and optional unit.
    fn quantity<'i>(&mut self, p: P<'i>) -> (String, f64, Option<(String, Span)>, Span) {
        let s = span(&p);
        let mut number = String::new();
        let mut unit = None;
        for k in p.into_inner() {
            match k.as_rule() {
                Rule::number => number = k.as_str().to_owned(),
                Rule::unit => unit = Some((k.as_str().to_owned(), span(&k))),
                _ => {}
            }
        }
        let value = match number.parse::<f64>() {
            Ok(v) if v.is_finite() => v,
            _ => {
                self.errors.push(SyntaxError::BadNumber {
                    span: s,
                    found: number.clone(),
                });
                0.0
            }
        };
        (number, value, unit, s)
    }

    /// A size-like length (cube edge, suction, lift, jitter).
    fn length(&mut self, p: P) -> Length {
        self.length_with(p, true)
    }

    fn length_with(&mut self, p: P, is_size: bool) -> Length {
        let (number, value, unit, s) = self.quantity(p);
        let unit = match unit {
            None => {
                if is_size && value.abs() > MAX_BARE_METRES {
                    self.errors.push(SyntaxError::MissingUnit {
                        span: s,
                        number: number.clone(),
                    });
                }
                None
            }
            Some((u, us)) => match u.as_str() {
                "mm" => Some(LengthUnit::Mm),
                "cm" => Some(LengthUnit::Cm),
                "m" => Some(LengthUnit::M),
                _ => {
                    self.errors.push(SyntaxError::UnknownUnit {
                        span: us,
                        unit: u,
                        allowed: "`mm`, `cm` or `m` (or no unit for metres)",
                    });
                    None
                }
            },
        };
        Length {
            metres: value * unit.map_or(1.0, LengthUnit::metres),
            number,
            unit,
            span: s,
        }
    }

    fn mass(&mut self, p: P) -> Mass {
        let (number, value, unit, s) = self.quantity(p);
        let unit = match unit {
            None => None,
            Some((u, us)) => match u.as_str() {
                "kg" => Some(MassUnit::Kg),
                "g" => Some(MassUnit::G),
                _ => {
                    self.errors.push(SyntaxError::UnknownUnit {
                        span: us,
                        unit: u,
                        allowed: "`kg` or `g` (or no unit for kilograms)",
                    });
                    None
                }
            },
        };
        let kg = if unit == Some(MassUnit::G) {
            value / 1000.0
        } else {
            value
        };
        Mass {
            kg,
            number,
            unit,
            span: s,
        }
    }

    fn count(&mut self, p: P, what: &'static str) -> Count {
        let (number, _, unit, s) = self.quantity(p);
        if let Some((_, us)) = unit {
            self.errors
                .push(SyntaxError::UnexpectedUnit { span: us, what });
        }
        match number.parse::<u64>() {
            Ok(value) => Count { value, span: s },
            Err(e) => {
                // All digits, and more than a u64 holds: too large, not
                // "not a whole number" (helper W).
                let too_large = *e.kind() == std::num::IntErrorKind::PosOverflow;
                self.errors.push(if too_large {
                    SyntaxError::WholeNumberTooLarge {
                        span: s,
                        what,
                        found: number,
                    }
                } else {
                    SyntaxError::NotWholeNumber {
                        span: s,
                        what,
                        found: number,
                    }
                });
                Count { value: 0, span: s }
            }
        }
    }

    /// A time: `ms` or `s`, or a bare number of seconds.
    fn time(&mut self, p: P) -> Time {
        let (number, value, unit, s) = self.quantity(p);
        let unit = match unit {
            None => None,
            Some((u, us)) => match u.as_str() {
                "ms" => Some(TimeUnit::Ms),
                "s" => Some(TimeUnit::S),
                _ => {
                    self.errors.push(SyntaxError::UnknownUnit {
                        span: us,
                        unit: u,
                        allowed: "`ms` or `s` (or no unit for seconds)",
                    });
                    None
                }
            },
        };
        Time {
            seconds: value * unit.map_or(1.0, TimeUnit::seconds),
            number,
            unit,
            span: s,
        }
    }

    /// A share: a number with `%`, or a plain fraction (`allowed` says
    /// so for the statement's unit error).
    fn share(&mut self, p: P, allowed: &'static str) -> Share {
        let (number, value, unit, s) = self.quantity(p);
        let percent = match unit {
            None => false,
            Some((u, _)) if u == "%" => true,
            Some((u, us)) => {
                self.errors.push(SyntaxError::UnknownUnit {
                    span: us,
                    unit: u,
                    allowed,
                });
                false
            }
        };
        Share {
            value: if percent { value / 100.0 } else { value },
            number,
            percent,
            span: s,
        }
    }

    /// A parenthesised list of plain numbers, one per joint.
    fn joint_values(&mut self, p: P, what: &'static str) -> JointValues {
        let s = span(&p);
        let values = p
            .into_inner()
            .filter(|q| q.as_rule() == Rule::quantity)
            .map(|q| self.fraction(q, what))
            .collect();
        JointValues { values, span: s }
    }

    fn fraction(&mut self, p: P, what: &'static str) -> Fraction {
        let (number, value, unit, s) = self.quantity(p);
        if let Some((_, us)) = unit {
            self.errors
                .push(SyntaxError::UnexpectedUnit { span: us, what });
        }
        Fraction {
            value,
            number,
            span: s,
        }
    }
}

fn name(p: &P) -> Name {
    Name {
        text: p.as_str().to_owned(),
        span: span(p),
    }
}

fn missing_name(s: Span) -> Name {
    Name {
        text: String::new(),
        span: s,
    }
}

fn zero_length(s: Span) -> Length {
    Length {
        metres: 0.0,
        number: "0".into(),
        unit: None,
        span: s,
    }
}

fn zero_point(s: Span) -> Point {
    Point {
        x: zero_length(s),
        y: zero_length(s),
        z: None,
        span: s,
    }
}

/// The last child of a statement (its value).
fn last(p: P) -> P {
    let s = p.clone();
    kids(p).last().unwrap_or(s)
}

fn names_of(p: P) -> Vec<Name> {
    let mut out = Vec::new();
    for k in p.into_inner() {
        match k.as_rule() {
            Rule::name => out.push(name(&k)),
            Rule::names => out.extend(names_of(k)),
            _ => {}
        }
    }
    out
}

fn seq_mode(p: &P) -> SequenceMode {
    match p.as_str() {
        "descending" => SequenceMode::Descending,
        "listed" => SequenceMode::Listed,
        "random" => SequenceMode::Random,
        _ => SequenceMode::Ascending,
    }
}

fn string(p: &P) -> Str {
    let raw = p
        .clone()
        .into_inner()
        .find(|k| k.as_rule() == Rule::string_inner)
        .map_or("", |k| k.as_str());
    let mut value = String::with_capacity(raw.len());
    let mut chars = raw.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => value.push('\n'),
                Some('t') => value.push('\t'),
                Some(other) => value.push(other),
                None => {}
            }
        } else {
            value.push(c);
        }
    }
    Str {
        value,
        span: span(p),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A text of stray lines (a file that is not a `.pack` file) gives
    /// one error a line up to [`MAX_SYNTAX_ERRORS`], then one saying the
    /// parse stopped, at the next line: a million stray lines took
    /// gigabytes to report.
    /// `5e-2` is read as `5` with the unit `e`, then `-2`: the error
    /// suggests the number written plainly.
    #[test]
    fn a_number_in_scientific_notation_gets_it_written_plainly() {
        for (text, plain) in [
            ("product q cube 5e-2\n", "0.05"),
            ("product q cube 5E1 mm\n", "50"),
            ("product q cube 2.5e-2 mass 1\n", "0.025"),
        ] {
            let errors = parse(text).expect_err(text);
            let first = errors.first().expect("an error");
            assert_eq!(first.code(), "E006");
            let help = first.help().unwrap_or_default();
            assert!(
                help.starts_with(&format!("write `{plain}`")),
                "{text}: {help}"
            );
            // The caret is under the whole number.
            let span = first.span();
            let under = &text[span.start as usize..span.end as usize];
            assert!(under.starts_with(|c: char| c.is_ascii_digit()), "{under}");
            assert!(under.contains(['e', 'E']), "{under}");
        }
    }

    /// A count longer than a whole number holds is said to be too large
    /// (helper W: "must be a whole number, 0 or more, found
    /// `99999999999999999999`"); a negative one is still not a whole
    /// number.
    #[test]
    fn a_count_too_large_is_told_so() {
        let block = |n: &str| format!("scenarios s for inv {{\n  count {n}\n}}\n");
        let errors = parse(&block("99999999999999999999")).expect_err("too large");
        assert!(
            matches!(
                errors.first(),
                Some(SyntaxError::WholeNumberTooLarge { .. })
            ),
            "{errors:?}"
        );
        let first = &errors[0];
        assert_eq!(first.code(), "E005");
        assert!(first.to_string().contains("too large"), "{first}");
        let errors = parse(&block("-1")).expect_err("negative");
        assert!(
            matches!(errors.first(), Some(SyntaxError::NotWholeNumber { .. })),
            "{errors:?}"
        );
    }

    /// An exponent that writes no usable number (helper W: `1e400` was
    /// E001 at `400`, `1e308`'s help wrote 309 digits, `1e-400`'s said
    /// `0`) is E006 with a help that says so.
    #[test]
    fn an_exponent_beyond_any_cell_says_so() {
        for text in [
            "product q cube 1e400\n",
            "product q cube 1e308\n",
            "product q cube 1e-400\n",
        ] {
            let errors = parse(text).expect_err(text);
            let first = errors.first().expect("an error");
            assert_eq!(first.code(), "E006", "{text}: {first}");
            let help = first.help().unwrap_or_default();
            assert!(help.contains("far beyond"), "{text}: {help}");
        }
    }

    #[test]
    fn a_parse_stops_after_so_many_syntax_errors() {
        let errors = parse(&"x\n".repeat(MAX_SYNTAX_ERRORS + 500)).expect_err("stray lines");
        assert_eq!(errors.len(), MAX_SYNTAX_ERRORS + 1);
        assert!(
            errors[..MAX_SYNTAX_ERRORS]
                .iter()
                .all(|e| matches!(e, SyntaxError::Unexpected { .. }))
        );
        let last = errors.last().expect("the stop");
        assert!(matches!(last, SyntaxError::TooMany { .. }), "{last:?}");
        assert_eq!(last.span().start, 2 * MAX_SYNTAX_ERRORS as u32);
        // Fewer errors than that: no stop.
        let few = parse(&"x\n".repeat(10)).expect_err("stray lines");
        assert_eq!(few.len(), 10);
    }
    /// A rate (`deg/s`) is one unknown unit under one caret, as `deg` is,
    /// not a stray `/` after a unit.
    #[test]
    fn a_rate_is_one_unknown_unit() {
        let cell = |stmt: &str| format!("cell c {{\n  {stmt}\n}}\n");
        for (stmt, unit) in [
            ("speed 30 deg/s", "deg/s"),
            ("speed 30 deg", "deg"),
            ("lift 150 mm/s", "mm/s"),
        ] {
            let text = cell(stmt);
            let errors = parse(&text).expect_err(stmt);
            let [
                SyntaxError::UnknownUnit {
                    span, unit: found, ..
                },
            ] = errors.as_slice()
            else {
                panic!("{stmt}: {errors:?}");
            };
            assert_eq!(found, unit);
            assert_eq!(&text[span.start as usize..span.end as usize], unit);
        }
    }

    /// A turn written on a box or an inventory's product is refused with a
    /// help that says the language has no yaw, not only the form without
    /// it; a word that is no turn keeps the plain help.
    #[test]
    fn a_yaw_gets_a_help_that_says_the_language_has_none() {
        for text in [
            "cell c {\n  box b (0, 0.6) size (0.3, 0.1, 0.08) yaw 30 deg\n}\n",
            "inventory s for c {\n  A (0.5, -0.2) Rotated 45\n}\n",
        ] {
            let errors = parse(text).expect_err(text);
            let help = errors
                .first()
                .and_then(SyntaxError::help)
                .unwrap_or_default();
            assert!(help.starts_with("the language has no yaw"), "{help}");
            assert!(help.contains("write it as `"), "{help}");
        }
        let errors = parse("cell c {\n  box b (0, 0.6) size (0.3, 0.1, 0.08) tall\n}\n")
            .expect_err("a stray word");
        let help = errors
            .first()
            .and_then(SyntaxError::help)
            .unwrap_or_default();
        assert!(help.starts_with("write it as `box"), "{help}");
    }
}
