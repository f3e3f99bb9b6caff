//! Where in a file a syntax error stands ([`Place`]), and how the
//! statements written there look: the help of a syntax error that has no
//! closer fix shows the statement its line starts with, written right
//! (`slot g1 (-0.12, 0.58)` for a bad `slot` line), or where a word
//! that belongs elsewhere goes (`mass` at the end of a product's line).
//!
//! Invariant: every example here is valid in its place (a unit test
//! parses each in a block of its own).

use std::fmt;

/// Where the parser was: at the top level, or in an item of one kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Place {
    TopLevel,
    Use,
    Cell,
    Product,
    Inventory,
    Order,
    Demo,
    Demos,
    Scenario,
    Scenarios,
}

/// How each statement of a place is written, by its first word. `None`
/// stands for any other word (an inventory's product, an order's
/// product).
type Forms = &'static [(Option<&'static str>, &'static str)];

const TOP_LEVEL: Forms = &[
    (Some("use"), "use \"cells/bench.pack\""),
    (Some("cell"), "cell bench { … }"),
    (Some("product"), "product A cube 50 mm"),
    (Some("inventory"), "inventory stock for bench { … }"),
    (Some("order"), "order hamper for stock { … }"),
    (Some("demo"), "demo seen for hamper { … }"),
    (Some("demos"), "demos teach for stock { … }"),
    (Some("scenario"), "scenario started for hamper { … }"),
    (Some("scenarios"), "scenarios case2 for stock { … }"),
];
const USE: Forms = &[(Some("use"), "use \"cells/bench.pack\"")];
const CELL: Forms = &[
    (Some("robot"), "robot ur10"),
    (Some("base"), "base (0, 0, 0)"),
    (Some("suction"), "suction 100 mm"),
    (Some("pending"), "pending (0.45, -0.5) to (0.85, -0.1)"),
    (Some("box"), "box tray (0, 0.65) size (0.4, 0.3, 0.08)"),
    (Some("slot"), "slot g1 (-0.12, 0.58)"),
    (Some("lift"), "lift 150 mm"),
    (Some("speed"), "speed 50 %"),
    (Some("settle"), "settle 100 ms after grip"),
    (Some("descent"), "descent 25 %"),
    (
        Some("acceleration"),
        "acceleration (2.5, 2.5, 2.5, 4, 4, 4)",
    ),
    (Some("jerk"), "jerk (10, 10, 10, 20, 20, 20)"),
];
const PRODUCT: Forms = &[
    (
        Some("product"),
        "product A cube 50 mm` or `product E box (60 mm, 40 mm, 50 mm) mass 0.3",
    ),
    (Some("mass"), "product E box (60 mm, 40 mm, 50 mm) mass 0.3"),
];
const INVENTORY: Forms = &[(None, "A (0.5, -0.2)")];
const ORDER: Forms = &[
    (Some("customer"), "customer \"ACME Ltd\""),
    (Some("batch"), "batch 500"),
    (None, "E -> g1"),
];
const DEMO: Forms = &[
    (Some("sequence"), "sequence A, E"),
    (Some("at"), "at E (0.69, -0.37)"),
];
const DEMOS: Forms = &[
    (Some("choose"), "choose 2 of A, E into g1, g2, g3"),
    (Some("keep"), "keep 0.5"),
    (Some("jitter"), "jitter 20 mm"),
    (Some("sequence"), "sequence ascending"),
    (Some("repeat"), "repeat 2"),
    (Some("seed"), "seed 1"),
    (Some("human"), "human packs 1 to 1"),
    (Some("missing"), "missing 0 to 1"),
];
const SCENARIO: Forms = &[
    (Some("human"), "human packed E"),
    (Some("missing"), "missing A"),
    (Some("jitter"), "jitter 20 mm"),
    (Some("seed"), "seed 3"),
    (Some("at"), "at E (0.69, -0.37)"),
];
const SCENARIOS: Forms = &[
    (Some("choose"), "choose 2 of A, E into g1, g2, g3"),
    (Some("human"), "human packs 1 to 1"),
    (Some("missing"), "missing 0 to 1"),
    (Some("jitter"), "jitter 20 mm"),
    (Some("count"), "count 100"),
    (Some("seed"), "seed 12"),
];

/// Every place, in the order a word that belongs elsewhere is looked up.
const PLACES: [Place; 10] = [
    Place::Product,
    Place::Cell,
    Place::Demos,
    Place::Scenarios,
    Place::Scenario,
    Place::Demo,
    Place::Order,
    Place::Use,
    Place::TopLevel,
    Place::Inventory,
];

impl Place {
    /// The place of an item whose first word is `word`: a product line
    /// missing its shape is "in a product", not "at the top level".
    pub fn of_item(word: Option<&str>) -> Place {
        match word {
            Some("use") => Place::Use,
            Some("cell") => Place::Cell,
            Some("product") => Place::Product,
            Some("inventory") => Place::Inventory,
            Some("order") => Place::Order,
            Some("demo") => Place::Demo,
            Some("demos") => Place::Demos,
            Some("scenario") => Place::Scenario,
            Some("scenarios") => Place::Scenarios,
            _ => Place::TopLevel,
        }
    }

    fn forms(self) -> Forms {
        match self {
            Place::TopLevel => TOP_LEVEL,
            Place::Use => USE,
            Place::Cell => CELL,
            Place::Product => PRODUCT,
            Place::Inventory => INVENTORY,
            Place::Order => ORDER,
            Place::Demo => DEMO,
            Place::Demos => DEMOS,
            Place::Scenario => SCENARIO,
            Place::Scenarios => SCENARIOS,
        }
    }

    /// What this place is, as the help names it.
    fn noun(self) -> &'static str {
        match self {
            Place::TopLevel => "a file",
            Place::Use => "a `use`",
            Place::Cell => "a cell",
            Place::Product => "a product",
            Place::Inventory => "an inventory",
            Place::Order => "an order",
            Place::Demo => "a demo",
            Place::Demos => "a `demos` block",
            Place::Scenario => "a scenario",
            Place::Scenarios => "a `scenarios` block",
        }
    }

    /// How a statement that starts with the keyword `word` is written
    /// here.
    fn form(self, word: &str) -> Option<&'static str> {
        self.forms()
            .iter()
            .find(|(w, _)| *w == Some(word))
            .map(|(_, form)| *form)
    }

    /// How a statement that starts with a name (no keyword) is written
    /// here: an inventory's or an order's line.
    fn named_form(self) -> Option<&'static str> {
        self.forms()
            .iter()
            .find(|(w, _)| w.is_none())
            .map(|(_, form)| *form)
    }

    /// The help for a syntax error on a statement that starts with `word`
    /// here: how that statement is written; for a word of another place's
    /// statement, where it goes; else a statement this place holds.
    pub fn help(self, word: Option<&str>) -> String {
        if let Some(word) = word {
            if let Some(form) = self.form(word) {
                return format!("write it as `{form}`");
            }
            let elsewhere = PLACES
                .iter()
                .filter(|p| **p != self)
                .find_map(|p| p.form(word).map(|form| (p, form)));
            if let Some((place, form)) = elsewhere {
                return match place {
                    Place::Product => {
                        format!("`{word}` is written on a product's line, as in `{form}`")
                    }
                    Place::TopLevel | Place::Use => {
                        format!("`{word}` starts a line of its own, as in `{form}`")
                    }
                    _ => format!("`{word}` is written inside {}, as `{form}`", place.noun()),
                };
            }
            if let Some(form) = self.named_form() {
                // A misspelt keyword reads as a name here (`custmoer`).
                let keywords = self.forms().iter().filter_map(|(w, _)| *w);
                if let Some(keyword) = crate::suggest::closest(word, keywords)
                    && let Some(meant) = self.form(keyword)
                {
                    return format!("did you mean `{keyword}`? write it as `{meant}`");
                }
                return format!("write it as `{form}`");
            }
        }
        let example = self.forms().first().map_or("", |(_, form)| *form);
        format!(
            "a line of {} is one statement, such as `{example}` (README, \"The language by example\")",
            self.noun()
        )
    }
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::TopLevel => f.write_str("at the top level"),
            place => write!(f, "in {}", place.noun()),
        }
    }
}

/// The first word of the statement that `pos` stands in: the text after
/// the last line end, `;` or `{` before it.
pub(crate) fn statement_word(src: &str, pos: usize) -> Option<&str> {
    let before = src.get(..pos.min(src.len()))?;
    let start = before.rfind(['\n', '\r', ';', '{']).map_or(0, |i| i + 1);
    let word: &str = src[start..]
        .trim_start_matches([' ', '\t'])
        .split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .next()?;
    (!word.is_empty()).then_some(word)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every example parses in a file of its own, with the blocks and
    /// names it needs around it.
    #[test]
    fn every_example_is_valid_where_it_is_written() {
        let unblock = |form: &str| form.replace(" { … }", " {\n}");
        let around = |place: Place, form: &str| -> String {
            match place {
                Place::TopLevel | Place::Use => unblock(form),
                Place::Product => form.split("` or `").collect::<Vec<_>>().join("\n"),
                Place::Cell => format!("cell c {{\n  {form}\n}}"),
                Place::Inventory => format!("inventory i for c {{\n  {form}\n}}"),
                Place::Order => format!("order o for i {{\n  {form}\n}}"),
                Place::Demo => format!("demo d for o {{\n  {form}\n}}"),
                Place::Demos => format!("demos d for i {{\n  {form}\n}}"),
                Place::Scenario => format!("scenario s for o {{\n  {form}\n}}"),
                Place::Scenarios => format!("scenarios s for i {{\n  {form}\n}}"),
            }
        };
        for place in PLACES {
            for (_, form) in place.forms() {
                let text = around(place, form);
                let parsed = crate::parse(&text);
                assert!(parsed.is_ok(), "{text}\n{parsed:?}");
            }
        }
    }

    #[test]
    fn the_help_shows_the_statement_the_line_starts_with() {
        assert_eq!(
            Place::Cell.help(Some("slot")),
            "write it as `slot g1 (-0.12, 0.58)`"
        );
        assert_eq!(Place::Order.help(Some("E")), "write it as `E -> g1`");
        assert_eq!(
            Place::Order.help(Some("custmoer")),
            "did you mean `customer`? write it as `customer \"ACME Ltd\"`"
        );
        assert_eq!(
            Place::Order.help(Some("slot")),
            "`slot` is written inside a cell, as `slot g1 (-0.12, 0.58)`"
        );
        assert_eq!(
            Place::TopLevel.help(Some("mass")),
            "`mass` is written on a product's line, as in `product E box (60 mm, 40 mm, 50 mm) mass 0.3`"
        );
        assert_eq!(
            Place::TopLevel.help(Some("slot")),
            "`slot` is written inside a cell, as `slot g1 (-0.12, 0.58)`"
        );
        assert!(
            Place::Cell
                .help(Some("g5"))
                .starts_with("a line of a cell is one statement")
        );
    }

    #[test]
    fn the_statement_word_is_the_first_after_a_line_end_a_semicolon_or_a_brace() {
        let src = "cell c {\n  slot g1 (0, x)\n  lift 1; speed 5\n}";
        let at = |s: &str| src.find(s).unwrap();
        assert_eq!(statement_word(src, at("x)")), Some("slot"));
        assert_eq!(statement_word(src, at("5")), Some("speed"));
        assert_eq!(statement_word(src, at("c {")), Some("cell"));
        assert_eq!(statement_word("", 0), None);
    }
}
