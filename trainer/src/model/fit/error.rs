//! Why a fit is refused.

/// Why a fit was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FitError {
    /// No poses were given.
    #[error("no poses to fit")]
    NoPoses,
    /// `angles` and `transfers` disagree on the number of poses.
    #[error("{angles} poses of angles but {transfers} of transfer")]
    PoseCountMismatch {
        /// Rows of the angle matrix.
        angles: usize,
        /// Transfer arrays.
        transfers: usize,
    },
    /// SH order 0 has no coefficients.
    #[error("SH order must be at least 1")]
    ZeroOrder,
    /// A transfer array is not `v · n²` long for the same `v` as pose 0.
    #[error(
        "pose {pose}: transfer has {len} values, expected {expected} (v · n² with n² = {coefs})"
    )]
    TransferLength {
        /// Pose index.
        pose: usize,
        /// Its length.
        len: usize,
        /// The length pose 0 implies (for pose 0: the next multiple of n²).
        expected: usize,
        /// n².
        coefs: usize,
    },
    /// The transfer arrays are empty (no vertices).
    #[error("transfer has no vertices")]
    NoVertices,
    /// A joint angle is NaN or infinite.
    #[error("pose {pose}: joint angle {joint} is not finite")]
    NonFiniteAngle {
        /// Pose index.
        pose: usize,
        /// Joint index.
        joint: usize,
    },
    /// A joint angle is beyond what the runtime's f32 pose vector can hold.
    #[error(
        "pose {pose}: joint angle {joint} is {value:e}, beyond ±3.4e38, the largest angle the runtime's f32 pose vector holds"
    )]
    AngleOutOfRange {
        /// Pose index.
        pose: usize,
        /// Joint index.
        joint: usize,
        /// The angle.
        value: f64,
    },
    /// A transfer value is NaN or infinite.
    #[error("pose {pose}: transfer value {index} is not finite")]
    NonFiniteTransfer {
        /// Pose index.
        pose: usize,
        /// Index into the vertex-major array.
        index: usize,
    },
    /// A fixed α must be finite and non-negative.
    #[error("alpha {0} must be finite and non-negative")]
    InvalidAlpha(f64),
    /// Energy fractions must lie in (0, 1].
    #[error("variance fraction {0} must lie in (0, 1]")]
    InvalidFraction(f64),
    /// A held-out segment must leave at least one pose to fit on.
    #[error("segment of {segment} poses leaves nothing to train on ({poses} poses)")]
    SegmentTooLong {
        /// Segment length.
        segment: usize,
        /// Number of poses.
        poses: usize,
    },
    /// The anchor's or a validation clip's shape disagrees with the training poses.
    #[error("{what}: {found}, expected {expected}")]
    HeldOutShape {
        /// The anchor or validation clip.
        what: String,
        /// What it has.
        found: String,
        /// What the training poses imply.
        expected: String,
    },
    /// The cosine features were asked for but would outnumber the runtime's limit.
    #[error(
        "{features} pose features (the angles and their cosines) exceed the runtime's {max}; use --features angles"
    )]
    TooManyFeatures {
        /// Features the cosines would make.
        features: usize,
        /// The runtime's limit.
        max: usize,
    },
    /// The local model was asked for alone but cannot be fitted.
    #[error("the local model cannot be fitted: {0}")]
    NoLocalModel(&'static str),
    /// Every α of the grid left some held-out set unpredictable.
    #[error("cross validation error is infinite for every alpha")]
    NoFiniteCvError,
}
