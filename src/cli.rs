//! Command-line arguments (clap derive). The help texts are the first
//! documentation most users read: they say what each command does, what it
//! writes, and how it exits.

use clap::{ArgGroup, Args, Parser, Subcommand};
use packwright_interface::PlannerKind;
use std::path::PathBuf;

#[derive(Debug, Parser)]
#[command(
    name = "packwright",
    version,
    about = "Teach a UR10 cobot to pack customer orders from a few demonstrations",
    long_about = "Teach a UR10 cobot to pack customer orders from a few demonstrations.\n\n\
Cells, products, inventories, orders, demonstrations and test scenarios are written in \
`.pack` files. `check` finds their mistakes, every one of a kind at once: syntax first, \
then names, then geometry, reach and counts (a later kind is looked for once the earlier \
ones are fixed); `compile` turns them into graph \
datasets and goal-label tables for training; `show` summarises compiled artifacts; \
`fmt` lays files out canonically.",
    after_help = "Exit codes: 0 success; 1 diagnostics in the input (or `fmt --check` found \
files to format); 2 bad usage, unreadable files, failed writes or internal errors.\n\
Data goes to stdout; diagnostics, progress and logs to stderr."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

impl Cli {
    /// Whether the command was asked for `--json`: an error that stops it
    /// is then printed on stdout as a JSON object too.
    pub fn wants_json(&self) -> bool {
        match &self.command {
            Command::Check(a) => a.json,
            Command::Compile(a) => a.json,
            Command::Show(a) => a.json,
            Command::Execute(a) => a.json,
            Command::Demonstrate(a) => a.json,
            Command::Train(a) => a.json,
            Command::Eval(a) => a.json,
            Command::Draw(_) | Command::Fmt(_) | Command::Generate(_) | Command::Chart(_) => false,
        }
    }
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Check .pack files (and the files they `use`) and report every error.
    ///
    /// Each error names its file, line and column, shows the line with a
    /// caret under the mistake, and says how to fix it. Nothing is written.
    Check(CheckArgs),
    /// Compile .pack files into training artifacts in a directory.
    ///
    /// Writes manifest.json, labels.json, orders.json, scenarios.json,
    /// demonstrations.jsonl, combinations.jsonl and graphs.safetensors
    /// (see the README for their format). Demonstrations are streamed to
    /// the files, so memory stays small however many are generated. The
    /// directory is written atomically: it is replaced only after every
    /// file is complete, and only if it is empty or holds earlier
    /// artifacts. The same inputs always give the same bytes.
    Compile(CompileArgs),
    /// Summarise a directory of compiled artifacts.
    Show(ShowArgs),
    /// Draw a cell as an SVG picture, in top and side view at true scale.
    ///
    /// Shows the robot base and its reachable annulus (0.20 to 1.30 m for
    /// the UR10), the pending area, the boxes and their slots (name and
    /// label), and, with `--inventory`, `--order` or `--scenario`, the
    /// products at their positions (footprint and name), the order's
    /// assignment as arrows, and a scenario's worker-packed and missing
    /// products. Diagnostics that `check` finds are drawn where they are
    /// (a slot outside its box circled in red) and listed under the
    /// picture and on stderr; the picture is still written, and the exit
    /// code is 1. A scenario needs files without diagnostics.
    ///
    /// Example: `packwright draw orders/customers/hampton_deli.pack --order
    /// deli_crate -o deli.svg`. Without `-o` the SVG goes to stdout.
    Draw(DrawArgs),
    /// Pack an order in the physical simulator, or on a real UR10
    /// (`--robot ur10://HOST`), and report each product.
    ///
    /// The order (or a scenario: products a worker already packed, missing
    /// stock, jittered positions) is packed by the learned planner, the
    /// scripted expert or RRT-Connect, with jerk-limited (Ruckig) motion at
    /// the UR10's 2 ms control cycle. Prints one row per product: planning
    /// time, execution time, final distance from the slot goal, outcome. Exit 0
    /// when the package is complete, 1 when it is not (the arm stopped
    /// safely, or products wait for restocking), 2 on bad input.
    Execute(ExecuteArgs),
    /// Record the expert's motion demonstrations for compiled demos.
    ///
    /// Replays every demonstration of a compiled directory in the
    /// simulator with the scripted expert, in its demonstrated sequence,
    /// and writes, for every sub-goal, what the sub-goal planner observes
    /// (feature, tool position, label) and the sub-goal reached, plus 20
    /// (delta, joint action) samples along the way (tensor names in the
    /// README). Exit 1 if some demonstration could not be replayed (the
    /// others are written).
    Demonstrate(DemonstrateArgs),
    /// Learn the reasoner, the sub-goal planner and the dynamics policy.
    ///
    /// Replays the compiled demonstrations with the scripted expert in the
    /// simulator to record motion, then trains the three networks (Adam,
    /// seeded, early stopping on a 20% held-out split) and writes
    /// config.json, reasoner.safetensors, subgoal.safetensors,
    /// dynamics.safetensors and metrics.json. Exit 1 if some
    /// demonstration could not be replayed (the model is still written).
    Train(TrainArgs),
    /// Measure success rates and planning times over scenario suites.
    ///
    /// Runs every scenario of the suites in the simulator (in parallel)
    /// with the learned planner and, with `--baselines`, RRT-Connect and
    /// the expert, and prints per suite and planner: the reasoner's success
    /// rate (every decision right), the whole system's success rate with a
    /// Wilson 95% interval, with and without fallbacks, fallbacks per
    /// package, planning time per decision and per sub-goal (median and
    /// p99, microseconds) and simulated execution time per product; with
    /// more than one suite, the same per planner over every scenario of
    /// the run (`totals` in `--json`).
    Eval(EvalArgs),
    /// Lay out .pack files canonically (comments are kept).
    ///
    /// Rewrites each file in place, atomically, unless `--check` or
    /// `--stdout` is given.
    Fmt(FmtArgs),
    /// Write random valid cells (gen_SEED.pack), for tests and benchmarks.
    ///
    /// Each seed gives one self-contained .pack file, the same bytes on
    /// every machine: a UR10 cell (its base off the origin, sometimes on a
    /// riser; the box in front of, behind, left or right of the robot, the
    /// products waiting on another side, all within comfortable reach), 4
    /// to 10 products of varied sizes, one inventory, and sparse teaching:
    /// one `demos` block of n = 2 or 3 products, half of the combinations,
    /// one or two slots never used, packed ascending, descending or in a
    /// listed order (40 to 200 demonstrations).
    ///
    /// Six suites of 50 scenarios measure what the demonstrations did not
    /// show: gen_SEED_case1_n, gen_SEED_case1_n1 and gen_SEED_case1_n2
    /// (CASE 1 with n, n + 1 and n + 2 products, any slot),
    /// gen_SEED_case2 (a worker packs some products first),
    /// gen_SEED_missing (1 or 2 out of stock) and gen_SEED_untaught (every
    /// package uses a slot no demonstration used). Every file passes
    /// `check` and `fmt --check`.
    ///
    /// Develop on many random cells, so that nothing is tuned to one cell;
    /// report on fixed seeds, so that figures can be compared
    /// (scripts/family.sh compiles, trains and evaluates a list of seeds).
    /// Files are written atomically; their paths are printed on stdout.
    Generate(GenerateArgs),
    /// Chart a study: success against a quantity varied across several
    /// `eval --json` runs (a training ratio, say), and against n.
    ///
    /// Each run is given as VALUE=FILE: an `eval --json` report and the
    /// value of the studied quantity it was run at. Writes two SVG files
    /// into DIR: success_vs_x.svg (one line per suite, the success rate
    /// with its Wilson 95% interval at each VALUE) and success_vs_n.svg
    /// (one line per VALUE, suites with the same number of products per
    /// order pooled). scripts/studies.sh trains and evaluates the paper's
    /// generalisation studies and calls this. Exit 0 when both are
    /// written, 2 on a missing or malformed report.
    ///
    /// Example: `packwright chart 0.25=keep25.json 0.5=keep50.json
    /// 1=all.json --x "training ratio" -o docs/studies`.
    Chart(ChartArgs),
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The .pack files to check; files they `use` are read too.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Print diagnostics as JSON Lines on stdout (one object per line,
    /// then a summary object).
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct CompileArgs {
    /// The .pack files to compile; files they `use` are read too.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// The output directory.
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
    /// Print the summary (or the diagnostics) as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct ShowArgs {
    /// A directory written by `packwright compile`.
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct DrawArgs {
    /// The .pack files that define the cell (files they `use` are read
    /// too).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// The cell to draw (default: the only cell the files define).
    #[arg(long, value_name = "NAME")]
    pub cell: Option<String>,
    /// Draw an inventory's products at their positions, in its cell.
    #[arg(long, value_name = "NAME", conflicts_with_all = ["cell", "order", "scenario"])]
    pub inventory: Option<String>,
    /// Draw an order: its inventory's products and its assignment as
    /// arrows, in its cell.
    #[arg(long, value_name = "NAME", conflicts_with_all = ["cell", "scenario"])]
    pub order: Option<String>,
    /// Draw a scenario (or a suite's case, such as `case1_3of5/007`): the
    /// jittered positions, the products a worker packed in their slots,
    /// the missing ones dashed.
    #[arg(long, value_name = "NAME", conflicts_with = "cell")]
    pub scenario: Option<String>,
    /// The SVG file to write (atomically); its path is printed on
    /// stdout. Without it, the SVG goes to stdout.
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// A count of at least 1 (`eval --limit 0` would measure nothing and
/// print an empty table).
fn at_least_one(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(0) => Err("must be at least 1".to_owned()),
        Ok(n) => Ok(n),
        Err(e) => Err(e.to_string()),
    }
}

fn planner(s: &str) -> Result<PlannerKind, String> {
    s.parse()
}

#[derive(Debug, Args)]
#[command(group(ArgGroup::new("task").required(true).args(["order", "scenario"])))]
pub struct ExecuteArgs {
    /// The .pack files that define the order (files they `use` are read too).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// The order to pack, with every product at its inventory position.
    #[arg(long, value_name = "NAME")]
    pub order: Option<String>,
    /// A scenario instead: a `scenario` name, or a case of a `scenarios`
    /// suite such as `case1_3of5/007`.
    #[arg(long, value_name = "NAME")]
    pub scenario: Option<String>,
    /// Who plans the motion: `expert` (the scripted demonstrator: straight
    /// joint motions between the sub-goals' inverse-kinematics solutions),
    /// `rrt` (the same sub-goals joined by RRT-Connect, the baseline) or
    /// `learned` (the reasoner chooses, the sub-goal planner and the
    /// dynamics policy move; RRT-Connect when a motion would collide or
    /// fall short). Default: `learned`, with `--model` or else the bundled
    /// model, on any cell (a note on stderr says when the model was not
    /// taught the order's cell).
    #[arg(long, value_name = "PLANNER", value_parser = planner)]
    pub planner: Option<PlannerKind>,
    /// A model directory written by `packwright train` (default: the
    /// bundled model, trained on line2 and 16 generated cells by
    /// scripts/train-default.sh).
    #[arg(long, value_name = "MODEL_DIR")]
    pub model: Option<PathBuf>,
    /// Seed of the RRT-Connect planner.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Also draw the executed tool path over the cell as an SVG file
    /// (written atomically): top and side view, coloured by stage
    /// (approach, carry, retreat), the sub-goals numbered (where the arm
    /// stopped or slowed), the start, each pick and release, fallbacks to
    /// RRT-Connect and the point where a failure stopped the arm. Simulated
    /// runs only.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
    /// Also record the run for the Rerun viewer as an .rrd file (written
    /// atomically): the arm's links as their collision capsules, the
    /// products and boxes, the tool path and sub-goals, the reasoner's
    /// decisions and scores, joint positions and velocities, picks,
    /// releases, collisions and fallbacks, on a `sim_time` timeline
    /// (entity paths in the README). View it with `rerun FILE` (`pip
    /// install rerun-sdk==0.36.*`). Needs a build with `--features
    /// rerun`; simulated runs only.
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// Pack on a real UR10 instead of the simulator (`sim`, the default):
    /// `ur10://HOST[:PORT]` or `ur://HOST[:PORT]` (RTDE port, default 30004; the secondary
    /// interface 30002 and the dashboard 29999 on the same host, or
    /// `?secondary=PORT&dashboard=PORT`). The robot must be powered on,
    /// brakes released, in remote control. Products are where the .pack
    /// file puts them (a jig) unless `--products-feed` is given. A stop
    /// (protective stop, lost connection, a refused command) stops the
    /// arm and exits 1 with the reason; re-arming is yours (README, "The
    /// real UR10").
    #[arg(long, value_name = "URL")]
    pub robot: Option<String>,
    /// With `--robot`: connect, read the joints, plan everything (in the
    /// simulator, from the measured joints), check the first command
    /// against them, and move nothing.
    #[arg(long, requires = "robot")]
    pub dry_run: bool,
    /// With `--robot`: product positions from a vision system, one JSON
    /// line per observation on a local socket (`HOST:PORT`), instead of
    /// the .pack file's positions.
    #[arg(long, value_name = "HOST:PORT", requires = "robot")]
    pub products_feed: Option<String>,
}

#[derive(Debug, Args)]
pub struct DemonstrateArgs {
    /// A directory written by `packwright compile`.
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
    /// The safetensors file to write.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct TrainArgs {
    /// A directory written by `packwright compile` with demonstrations.
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
    /// The model directory to write (replaced atomically).
    #[arg(short, long, value_name = "MODEL_DIR")]
    pub output: PathBuf,
    /// Learn from these `demo`/`demos` blocks only (default: all of them).
    /// They may be in several cells: one model then serves all of them and
    /// others like them (the bundled model learns from 17 cells); `train`
    /// infers one sequence rule from all of them.
    #[arg(long = "demos", value_name = "NAME", num_args = 1..)]
    pub demos: Vec<String>,
    /// Seed of the initial weights, the split and the batches.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Epochs per network over which the learning rate falls tenfold
    /// (early stopping on the held-out split usually ends sooner); a
    /// network still improving at N goes on at the final rate until a
    /// shorter plateau, to 2N epochs at most ("best epoch 2/2" for
    /// `--epochs 1`). At least 1.
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    pub epochs: Option<usize>,
    /// DAgger rounds for the dynamics policy (default 2; 0 learns from the
    /// demonstrations alone): the policy is rolled out from every
    /// demonstrated sub-goal start, the expert labels the states it
    /// visits, and it trains again on everything so far.
    #[arg(long, value_name = "N")]
    pub dagger_rounds: Option<usize>,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
    /// Print the metrics as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The .pack files with the `scenarios` suites (files they `use` are
    /// read too).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// A model directory written by `packwright train` (default: the
    /// bundled model).
    #[arg(long, value_name = "MODEL_DIR")]
    pub model: Option<PathBuf>,
    /// Evaluate these suites only (default: every suite in the files).
    #[arg(long = "suite", value_name = "NAME", num_args = 1..)]
    pub suites: Vec<String>,
    /// Also run the RRT-Connect and expert planners on every scenario.
    #[arg(long)]
    pub baselines: bool,
    /// Only the reasoner's decisions, no motion (fast).
    #[arg(long)]
    pub reasoner_only: bool,
    /// The first N scenarios of each suite only (at least 1).
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    pub limit: Option<usize>,
    /// Seed of RRT-Connect (scenario i uses seed + i): a run is
    /// reproducible from it.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Also write the table as Markdown to FILE.
    #[arg(long, value_name = "FILE")]
    pub markdown: Option<PathBuf>,
    /// Also write SVG charts into DIR (created if needed; files of the
    /// same names replaced): success_rate.svg (each suite and planner's
    /// success rate with its Wilson 95% interval), latency.svg (planning
    /// time per decision, per sub-goal and per sub-goal + action, as
    /// distributions on a log axis) and execution_time.svg (each packed
    /// product's simulated execution time against its lower bound).
    #[arg(long, value_name = "DIR")]
    pub plots: Option<PathBuf>,
    /// Also record every scenario's runs for the Rerun viewer: one file
    /// per scenario, named as the scenario (`case1_3of5/007` is
    /// DIR/case1_3of5/007.rrd; directories created if needed, files of
    /// the same names replaced, each written atomically), one recording
    /// per planner in each file; see `execute --record`. Needs a build
    /// with `--features rerun`.
    #[arg(long, value_name = "DIR", conflicts_with = "reasoner_only")]
    pub record: Option<PathBuf>,
    /// Print every figure as JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Which success rate a study charts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum StudyMetric {
    /// The reasoner's: every decision of a scenario right.
    Reasoner,
    /// The whole system's: the package complete (fallbacks allowed).
    System,
    /// The whole system's without any fallback to the expert.
    NoFallback,
}

fn study_run(s: &str) -> Result<(f64, PathBuf), String> {
    let (value, file) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}` is not VALUE=FILE (for example 0.25=run.json)"))?;
    let x: f64 = value
        .trim()
        .parse()
        .map_err(|_| format!("`{value}` in `{s}` is not a number"))?;
    if !x.is_finite() {
        return Err(format!("`{value}` in `{s}` is not a finite number"));
    }
    if file.is_empty() {
        return Err(format!("`{s}` names no file after `=`"));
    }
    Ok((x, PathBuf::from(file)))
}

#[derive(Debug, Args)]
pub struct ChartArgs {
    /// The runs of the study, each as VALUE=FILE: the value of the studied
    /// quantity and the `packwright eval --json` report run at it.
    #[arg(required = true, value_name = "VALUE=FILE", value_parser = study_run)]
    pub runs: Vec<(f64, PathBuf)>,
    /// What VALUE is: the x axis of success_vs_x.svg and the legend of
    /// success_vs_n.svg.
    #[arg(long, value_name = "NAME", default_value = "training ratio")]
    pub x: String,
    /// The success rate charted.
    #[arg(long, value_enum, default_value_t = StudyMetric::Reasoner)]
    pub metric: StudyMetric,
    /// The planner whose rows are charted (learned, rrt or expert).
    #[arg(long, value_name = "PLANNER", value_parser = planner, default_value = "learned")]
    pub planner: PlannerKind,
    /// The directory for the two SVG files (created if needed; files of
    /// the same names replaced, each written atomically).
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
}

#[derive(Debug, Args)]
pub struct FmtArgs {
    /// The .pack files to format.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Write nothing; list the files that are not formatted and exit 1 if
    /// there are any.
    #[arg(long, conflicts_with = "stdout")]
    pub check: bool,
    /// Print the formatted text on stdout instead of rewriting the files.
    #[arg(long)]
    pub stdout: bool,
}

/// The most cells one `generate` makes: all are made in memory before any
/// is written (so that none replaces an edited file).
pub const MAX_GENERATED: u64 = 10_000;

#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// The first seed: the cell `gen_SEED`, written to DIR/gen_SEED.pack.
    #[arg(long, value_name = "SEED")]
    pub seed: u64,
    /// How many cells: seeds SEED to SEED + COUNT - 1 (at most 10000 in
    /// one run).
    #[arg(long, value_name = "COUNT", default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=MAX_GENERATED))]
    pub count: u64,
    /// The directory to write into (created if needed; a file of the same
    /// name is replaced only if it is what its seed generates: one edited
    /// since is kept, and nothing is written, exit 2).
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
    /// Teach every cell in this order instead of the seed's own (the rest
    /// of each cell stays the seed's): cells that teach one model together
    /// must agree on the order, since `train` infers one rule from all its
    /// demonstrations.
    #[arg(long, value_enum, value_name = "RULE")]
    pub sequence: Option<TaughtOrder>,
    /// Which cells to draw. `standard` is what the bundled model was taught
    /// on and the README reports on (gen_SEED.pack); `wide` draws the same
    /// recipe with what a line engineer's cell may have and ours rarely
    /// does: boxes to 300 mm deep, products to 150 mm tall, lifts from 20
    /// mm, cups 50-200 mm, risers to 400 mm, half of the cells slowed with
    /// `speed` (wide_SEED.pack); `compact` the standard sizes with the
    /// products waiting beside the box, on the same side of the robot
    /// (compact_SEED.pack). Develop on wide and compact cells to find what
    /// the standard ones hide.
    #[arg(long, value_enum, value_name = "FAMILY", default_value_t = CellFamily::Standard)]
    pub family: CellFamily,
    /// Teach each cell as a line engineer would, with K hand-written
    /// `order` + `demo` pairs (2 or 3 products each, in the taught slots,
    /// demonstrated once in the cell's rule) instead of the generated
    /// `demos` block. The cell and its suites stay the seed's.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u8).range(1..=20))]
    pub hand: Option<u8>,
    /// Add a second inventory of the same products with their places
    /// reversed, and draw every suite from it: products waiting where no
    /// demonstration picked them.
    #[arg(long)]
    pub reversed_stock: bool,
}

/// The cells `generate` draws (`--family`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CellFamily {
    /// Boxes 60-100 mm deep, products 25-60 mm, lifts 100-200 mm.
    Standard,
    /// Deep boxes, tall products, short lifts, long cups, high risers.
    Wide,
    /// Standard sizes; the products wait beside the box.
    Compact,
}

/// A sequence rule `generate` can teach (`--sequence`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TaughtOrder {
    /// Inventory order.
    Ascending,
    /// Inventory order reversed.
    Descending,
    /// A priority list other than the inventory order.
    Listed,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_count_is_at_least_one() {
        assert_eq!(at_least_one("3"), Ok(3));
        assert_eq!(at_least_one("0"), Err("must be at least 1".to_owned()));
        assert!(at_least_one("-1").is_err());
        assert!(Cli::try_parse_from(["packwright", "eval", "a.pack", "--limit", "0"]).is_err());
        assert!(Cli::try_parse_from(["packwright", "eval", "a.pack", "--limit", "2"]).is_ok());
    }
}
