//! The robot-model crate's error: a robot description that cannot be used.

use thiserror::Error;

/// Why a URDF description is refused.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum UrdfError {
    /// Not URDF XML (urdf-rs's words).
    #[error("robot description: invalid URDF: {reason}")]
    Parse { reason: String },
    #[error("robot description: two links have the same name")]
    DuplicateLink,
    #[error("robot description: joint `{joint}` names an unknown link `{link}`")]
    UnknownLink { joint: String, link: String },
    #[error(
        "robot description: link `{link}` is the child of two joints (`{first}` and `{second}`): not a chain"
    )]
    TwoParents {
        link: String,
        first: String,
        second: String,
    },
    #[error("robot description: the description has no links")]
    NoLinks,
    #[error("robot description: the joints form a loop: no root link")]
    Loop,
    #[error("robot description: several root links ({}): the description must be one chain", roots.join(", "))]
    SeveralRoots { roots: Vec<String> },
    #[error(
        "robot description: the chain branches at link `{link}` (joints {}): only a single chain is supported",
        joints.join(", ")
    )]
    Branches { link: String, joints: Vec<String> },
    #[error(
        "robot description: `{robot}` has more than 6 movable joints (`{joint}` is the 7th): packwright drives 6-axis arms"
    )]
    TooManyJoints { robot: String, joint: String },
    #[error("robot description: joint `{joint}` has no valid axis")]
    NoAxis { joint: String },
    /// A prismatic, floating or planar joint.
    #[error(
        "robot description: joint `{joint}` is {kind}: only revolute, continuous and fixed joints are supported"
    )]
    JointKind { joint: String, kind: String },
    #[error(
        "robot description: `{robot}` has {found} movable joints along its chain; packwright needs exactly 6"
    )]
    JointCount { robot: String, found: usize },
    #[error("robot description: {what} has a non-finite origin")]
    Origin { what: String },
    #[error(
        "robot description: revolute joint `{joint}` needs a <limit> with finite lower < upper (found {lower} .. {upper})"
    )]
    PositionLimits {
        joint: String,
        lower: f64,
        upper: f64,
    },
    #[error(
        "robot description: joint `{joint}` needs a <limit> velocity of at least {min} rad/s, not {velocity}: URDF velocities are in rad/s (the UR10's are 2.09 to 3.14)"
    )]
    Velocity {
        joint: String,
        velocity: f64,
        min: f64,
    },
    /// A joint's acceleration or jerk limit outside the bounds of sense a
    /// cell's own `acceleration` and `jerk` statements have.
    #[error(
        "robot description: joint `{joint}`'s <limit> {what} is {}, outside {lower}-{upper} {unit}: the smoothing keeps every motion within it, so a value this far off is a typo or another unit (a cell's `{what}` statement overrides the description's)",
        shown(*.value)
    )]
    Dynamics {
        joint: String,
        what: &'static str,
        value: f64,
        lower: f64,
        upper: f64,
        unit: &'static str,
    },
    /// A collision mesh that cannot be read or used.
    #[error(
        "robot description: link `{link}`: collision mesh `{file}`: {reason}. packwright bounds each collision mesh by a box or a capsule, so it reads the file (STL or OBJ, relative to the description, `package://` through ROS_PACKAGE_PATH or the description's folders); or describe the link by <box>, <cylinder>, <sphere> or <capsule>"
    )]
    Mesh {
        link: String,
        file: String,
        reason: String,
    },
    #[error("robot description: {what} has a non-positive or non-finite size")]
    Size { what: String },
    /// A collision shape larger than any arm ([`crate::urdf::MAX_SPAN`]):
    /// a description or mesh in millimetres.
    #[error(
        "robot description: {what} is {} m across, more than any arm ({max} m): URDF lengths are metres; a mesh exported in millimetres needs scale=\"0.001 0.001 0.001\" on its <mesh>, a description in millimetres every length divided by 1000",
        shown(*.across)
    )]
    ShapeTooLarge { what: String, across: f64, max: f64 },
    /// Joint origins adding up to more than any arm
    /// ([`crate::urdf::MAX_SPAN`]): a description in millimetres.
    #[error(
        "robot description: `{robot}`'s joints span {} m from the base joint to the flange, more than any arm ({max} m): URDF lengths are metres; a description exported in millimetres needs every origin and size divided by 1000",
        shown(*.span)
    )]
    SpanTooLong { robot: String, span: f64, max: f64 },
}

/// A number as a person reads it: plain where it is of a joint's scale,
/// else in scientific notation (1e300 was printed with all its digits).
fn shown(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}
