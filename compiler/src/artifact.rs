//! The JSON artifacts' schema (written by `emit`, read back by `show` and
//! the runtime). Field names are part of the documented format.

use crate::model::{DEFAULT_GRIP_SETTLE, DEFAULT_RELEASE_SETTLE};
use serde::{Deserialize, Serialize};

/// 2: demonstrations moved out of `manifest.json` into
/// `demonstrations.jsonl`, combinations into `combinations.jsonl`.
pub const SCHEMA_VERSION: u32 = 2;

/// The `schema` string of each artifact (for `graphs.safetensors`, the
/// value of its one metadata key, `schema`): written by `emit`, checked by
/// every reader.
pub mod schema {
    pub const MANIFEST: &str = "packwright.manifest";
    pub const LABELS: &str = "packwright.labels";
    pub const ORDERS: &str = "packwright.orders";
    pub const SCENARIOS: &str = "packwright.scenarios";
    /// Carries its version (`SCHEMA_VERSION`): the tensors have no field
    /// for it.
    pub const GRAPHS: &str = "packwright.graphs/2";
}

/// `manifest.json`
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    pub schema: String,
    pub version: u32,
    pub sources: Vec<SourceDigest>,
    pub counts: Counts,
    pub tensors: TensorShapes,
    pub demo_blocks: Vec<DemoBlockRecord>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SourceDigest {
    pub path: String,
    pub sha256: String,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
pub struct Counts {
    pub cells: usize,
    pub products: usize,
    pub inventories: usize,
    pub orders: usize,
    pub demo_blocks: usize,
    pub demonstrations: usize,
    pub samples: usize,
    pub suites: usize,
    pub scenarios: usize,
}

/// S, M and E of `graphs.safetensors`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
pub struct TensorShapes {
    pub samples: usize,
    pub nodes: usize,
    pub edges: usize,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct DemoBlockRecord {
    pub name: String,
    /// `demo` or `demos`.
    pub kind: String,
    pub cell: String,
    pub inventory: String,
    pub order: Option<String>,
    /// Goal configurations spanned before `keep`.
    pub configurations: u64,
    /// Combinations `keep` kept (listed in `combinations.jsonl`).
    pub kept_combinations: usize,
    /// Combinations left out by `keep`: unseen goal configurations to
    /// test on (listed in `combinations.jsonl`).
    pub held_out_combinations: usize,
    pub first_demonstration: usize,
    pub demonstrations: usize,
    pub samples: usize,
    /// A `demos` block with `sequence random`: any order is right (absent
    /// when false, so other blocks' bytes are as before).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub any_order: bool,
    /// A `demos` block with `sequence listed`: its `choose` list, the
    /// priority its demonstrations follow (absent for other blocks, so
    /// their bytes are as before).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub priority: Vec<String>,
    /// A `demos` block with `sequence descending` (absent when false): the
    /// direction it declares, which demonstrations of one product each
    /// cannot show.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub descending: bool,
}

/// A product and where it is, `[x, y, z]` in metres (z = centre height).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct At {
    pub product: String,
    pub at: [f64; 3],
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Assignment {
    pub product: String,
    pub slot: String,
    pub label: u32,
    /// Slot goal: (slot x, slot y, product height / 2).
    pub goal: [f64; 3],
}

/// One line of `combinations.jsonl`: a combination of a `demos` block's
/// products, kept for teaching or held out by `keep`. Each block's kept
/// combinations come first, then its held-out ones, each in
/// lexicographic order of the listed products.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CombinationRecord {
    pub block: String,
    pub kept: bool,
    pub products: Vec<String>,
}

/// One line of `demonstrations.jsonl` (line `i` is demonstration `i`, the
/// `demo` of the graph samples).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct DemonstrationRecord {
    pub block: String,
    pub cell: String,
    pub inventory: String,
    pub assignment: Vec<Assignment>,
    pub sequence: Vec<String>,
    pub human_packed: Vec<String>,
    pub missing: Vec<String>,
    /// Every present product at the start, in node order.
    pub start: Vec<At>,
    pub first_sample: usize,
    pub samples: usize,
}

/// `labels.json`
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct LabelsFile {
    pub schema: String,
    pub version: u32,
    pub cells: Vec<CellLabels>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CellLabels {
    pub cell: String,
    pub labels: Vec<Label>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Label {
    pub label: u32,
    /// `pick` or the slot's name.
    pub name: String,
    #[serde(rename = "box")]
    pub box_name: Option<String>,
    /// The slot's (x, y) on the box floor (z = 0); `null` for `pick`.
    pub position: Option<[f64; 2]>,
}

/// `orders.json`: the compiled world.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct WorldFile {
    pub schema: String,
    pub version: u32,
    pub cells: Vec<CellRecord>,
    pub products: Vec<ProductRecord>,
    pub inventories: Vec<InventoryRecord>,
    pub orders: Vec<OrderRecord>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "lowercase")]
pub enum RobotRecord {
    Ur10,
    /// Path to a URDF file.
    Urdf(String),
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CellRecord {
    pub name: String,
    pub robot: RobotRecord,
    pub base: [f64; 3],
    pub suction: f64,
    pub lift: f64,
    /// The arm's speed, a share of its full speed (absent in older
    /// artifacts: full speed).
    #[serde(default = "full_speed", skip_serializing_if = "at_full_speed")]
    pub speed: f64,
    /// Seconds the arm waits after the suction grips (absent in older
    /// artifacts and when the default: [`DEFAULT_GRIP_SETTLE`]).
    #[serde(
        default = "default_grip_settle",
        skip_serializing_if = "is_default_grip_settle"
    )]
    pub grip_settle: f64,
    /// Seconds the arm waits after the suction releases (absent in older
    /// artifacts and when the default: [`DEFAULT_RELEASE_SETTLE`]).
    #[serde(
        default = "default_release_settle",
        skip_serializing_if = "is_default_release_settle"
    )]
    pub release_settle: f64,
    /// The guarded descent's speed, a share of the cell's speed (absent in
    /// older artifacts and when 1: the cell's speed).
    #[serde(default = "full_speed", skip_serializing_if = "at_full_speed")]
    pub descent: f64,
    /// The arm's acceleration limits (rad/s², base first) in place of its
    /// own (absent: its own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub acceleration: Option<[f64; 6]>,
    /// The arm's jerk limits (rad/s³) in place of its own (absent: its own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jerk: Option<[f64; 6]>,
    pub pending: RectRecord,
    pub boxes: Vec<BoxRecord>,
    pub slots: Vec<SlotRecord>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RectRecord {
    pub min: [f64; 2],
    pub max: [f64; 2],
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct BoxRecord {
    pub name: String,
    pub centre: [f64; 2],
    pub size: [f64; 3],
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SlotRecord {
    pub name: String,
    pub label: u32,
    #[serde(rename = "box")]
    pub box_name: String,
    pub position: [f64; 2],
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ProductRecord {
    pub name: String,
    /// Width (x), depth (y), height (z).
    pub size: [f64; 3],
    pub mass: Option<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct InventoryRecord {
    pub name: String,
    pub cell: String,
    /// In the listed order (node order).
    pub products: Vec<At>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct OrderRecord {
    pub name: String,
    pub inventory: String,
    pub cell: String,
    pub customer: Option<String>,
    pub batch: Option<u64>,
    pub assignment: Vec<Assignment>,
}

/// `scenarios.json`
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ScenariosFile {
    pub schema: String,
    pub version: u32,
    pub suites: Vec<SuiteRecord>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SuiteRecord {
    pub name: String,
    /// `scenario` or `scenarios`.
    pub kind: String,
    pub cell: String,
    pub inventory: String,
    pub order: Option<String>,
    pub seed: u64,
    pub cases: Vec<CaseRecord>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CaseRecord {
    pub name: String,
    pub assignment: Vec<Assignment>,
    /// Already in their slots when the robot starts.
    pub human_packed: Vec<String>,
    /// Absent from the cell: the robot reports them as waiting.
    pub missing: Vec<String>,
    /// Every present product at the start, in node order.
    pub start: Vec<At>,
}

/// The tensor names of `graphs.safetensors`, in documented order (README,
/// "Artifacts"): emitted by `emit`, read by `show` and by training.
pub mod tensor {
    pub const NODES: &str = "nodes";
    pub const NODE_MASK: &str = "node_mask";
    pub const GOAL: &str = "goal";
    pub const TARGET: &str = "target";
    pub const LABEL: &str = "label";
    pub const STAGE: &str = "stage";
    pub const DEMO: &str = "demo";
    pub const EDGE_INDEX: &str = "edge_index";
    /// Every tensor, in documented order.
    pub const ALL: [&str; 8] = [
        NODES, NODE_MASK, GOAL, TARGET, LABEL, STAGE, DEMO, EDGE_INDEX,
    ];
}

/// The speed of a cell that declares none.
pub fn full_speed() -> f64 {
    1.0
}

fn at_full_speed(speed: &f64) -> bool {
    *speed == 1.0
}

/// The grip settle time of a cell that declares none.
pub fn default_grip_settle() -> f64 {
    DEFAULT_GRIP_SETTLE
}

fn is_default_grip_settle(s: &f64) -> bool {
    *s == DEFAULT_GRIP_SETTLE
}

/// The release settle time of a cell that declares none.
pub fn default_release_settle() -> f64 {
    DEFAULT_RELEASE_SETTLE
}

fn is_default_release_settle(s: &f64) -> bool {
    *s == DEFAULT_RELEASE_SETTLE
}
