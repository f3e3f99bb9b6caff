//! What a cell holds, in the robot half's own terms (it does not depend
//! on the compiler; `packwright-pipeline` translates compiled artifacts
//! into these). World frame: table top at z = 0, z up, metres.

/// A box (the package) on the table: a floor at the table and four thin
/// walls.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxSpec {
    pub name: String,
    /// Centre of the footprint on the table.
    pub centre: [f64; 2],
    /// Width (x), depth (y), height (z) of the outside.
    pub size: [f64; 3],
}

#[derive(Debug, Clone, PartialEq)]
pub struct SlotSpec {
    pub name: String,
    pub position: [f64; 2],
    /// Index into [`CellScene::boxes`].
    pub box_index: usize,
}

/// The fixed parts of a cell.
#[derive(Debug, Clone, PartialEq)]
pub struct CellScene {
    /// The cell's name in the `.pack` files.
    pub name: String,
    /// The robot base position (no rotation).
    pub base: [f64; 3],
    /// Length of the suction cup below the flange.
    pub suction: f64,
    /// How high a held product is carried above where it stood.
    pub lift: f64,
    /// The arm's speed, a share of its full speed (the arm's limits are
    /// scaled by it where the episode is built).
    pub speed: f64,
    /// Seconds the arm waits, still, after the suction grips a product
    /// (the vacuum builds up) before it lifts.
    pub grip_settle: f64,
    /// Seconds the arm waits, still, after the suction releases a product
    /// (it drops and comes to rest) before it backs up.
    pub release_settle: f64,
    /// The guarded descent onto a product's top face (from the hover to
    /// the contact), a share of the cell's speed in (0, 1]: that motion is
    /// slowed as [`speed`](CellScene::speed) slows every motion.
    pub descent: f64,
    /// The pending area's corners (min, max).
    pub pending: ([f64; 2], [f64; 2]),
    pub boxes: Vec<BoxSpec>,
    pub slots: Vec<SlotSpec>,
}

/// A product type.
#[derive(Debug, Clone, PartialEq)]
pub struct ProductSpec {
    pub name: String,
    /// Width (x), depth (y), height (z).
    pub size: [f64; 3],
    /// Kilograms.
    pub mass: f64,
}

/// Mass of a product whose mass is not given.
pub const DEFAULT_MASS: f64 = 0.2;

/// A product standing somewhere at the start (its centre).
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    pub product: ProductSpec,
    pub centre: [f64; 3],
}
