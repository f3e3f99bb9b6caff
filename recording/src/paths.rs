//! The entity paths and the timeline of a recording: stable names that
//! the README lists and the tests read back. World frame: z up, metres;
//! joint plots in radians and radians per second.

/// The timeline: seconds of simulated time since the start of the run.
pub const TIMELINE: &str = "sim_time";

/// The world (z up); everything 3D is under it.
pub const WORLD: &str = "world";

/// Link `i` of the arm (0 the fixed base link, 1 to 6 the moving links):
/// its collision capsules (and cuboids, if its description has any) in
/// the link's frame, moved by the link's pose every frame.
pub fn link(i: usize) -> String {
    format!("world/arm/link_{i}")
}

/// The suction cup, a capsule on the last link (it moves with it).
pub const CUP: &str = "world/arm/link_6/cup";

/// A product, as a box moved by its seen pose every frame.
pub fn product(name: &str) -> String {
    format!("world/products/{name}")
}

/// A box (the package), as a wireframe box; its slots are
/// [`slots`]`(name)`.
pub fn package(name: &str) -> String {
    format!("world/box/{name}")
}

/// The slots of a box, as labelled points on its floor.
pub fn slots(name: &str) -> String {
    format!("world/box/{name}/slots")
}

/// The pending area, as a rectangle on the table.
pub const PENDING: &str = "world/pending";

/// The executed tool path (the cup tip of the commanded joints), one
/// strip per stage run, coloured as `execute --svg` colours them
/// (approach, carry, retreat).
pub const TOOL_PATH: &str = "world/tool_path";

/// The sub-goals the arm reached (the cup tip at each, marked on the
/// path and numbered as `execute --svg` marks them), each from the time
/// it was reached.
pub const SUBGOALS_REACHED: &str = "world/subgoals/reached";

/// The learned planner's sub-goals, as its sub-goal planner gave them,
/// each from the time it was asked.
pub const SUBGOALS_PLANNED: &str = "world/subgoals/planned";

/// Measured position of joint `i` (0 the base), rad.
pub fn joint_position(i: usize) -> String {
    format!("plots/joints/q_{i}")
}

/// Measured velocity of joint `i`, rad/s.
pub fn joint_velocity(i: usize) -> String {
    format!("plots/joints/qd_{i}")
}

/// The suction: 1 on, 0 off.
pub const SUCTION: &str = "plots/suction";

/// The reasoner's decisions, as text (what it chose and every score).
pub const DECISIONS: &str = "reasoner/decisions";

/// The reasoner's scores at each decision, as bars: one per product
/// node in the taught chain order, then the box.
pub const SCORES: &str = "reasoner/scores";

/// The slot pointer's scores at each placing decision, as bars: one per
/// slot in the cell's order.
pub const SLOT_SCORES: &str = "reasoner/slot_scores";

/// Picks and releases (the suction switching).
pub const EVENTS_SUCTION: &str = "events/suction";

/// Contacts the world reported.
pub const EVENTS_COLLISIONS: &str = "events/collisions";

/// Stages the learned planner handed to RRT-Connect, and why.
pub const EVENTS_FALLBACKS: &str = "events/fallbacks";

/// Each product's outcome, decisions that broke the order, and the
/// package's verdict, at the end of the run.
pub const EVENTS_OUTCOME: &str = "events/outcome";
