//! Typed errors. Every error that comes from what the user gave (a file, an option) says which
//! file or option, where in it, and what is wrong; the CLI turns those into exit code 2.
//!
//! A bad value of an option is [`Error::Setting`], which names the option as a [`Setting`]: a
//! program (the `swarf` command among them) can match on it and say it in its own words (the
//! command names its flag); its [`Setting::name`] is the option's name in the library
//! (`link.ramp_angle_deg`, `spiral.zeta`, …).

use std::path::PathBuf;

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A bad input file: the file, the place in it, and the reason.
    #[error("{}: {place}: {reason}", file.display())]
    Input {
        /// The file.
        file: PathBuf,
        /// Where in it (`line 3 column 7`, `part[1].outer[4]`, …).
        place: String,
        /// What is wrong.
        reason: String,
    },
    /// A bad drawing (DXF, SVG).
    #[error(transparent)]
    Import(#[from] swarf_import::ImportError),
    /// A setting (an option of the library, or a value of the job) outside its range.
    #[error("{}: {reason}", setting.name())]
    Setting {
        /// Which one.
        setting: Setting,
        /// The value and what is wrong with it.
        reason: String,
    },
    /// A job that cannot be machined as asked: the tool fits nowhere, nothing is left to cut, …
    #[error("{place}: {reason}")]
    Job {
        /// The aspect of the job (`tool diameter`, `stock`, `medial strategy`, …).
        place: String,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// An output could not be made (a picture that cannot be rendered or encoded).
    #[error("{what}: {reason}")]
    Output {
        /// The output.
        what: String,
        /// What went wrong.
        reason: String,
    },
    /// An output refused before anything is written: it is one of the inputs, not a regular
    /// file, or named twice ([`crate::io::output`]).
    #[error("{}: {reason}", file.display())]
    Refused {
        /// The output asked for.
        file: PathBuf,
        /// Why it is refused.
        reason: String,
    },
}

impl Error {
    /// A setting error.
    pub fn setting(setting: Setting, reason: impl Into<String>) -> Self {
        Error::Setting { setting, reason: reason.into() }
    }
    /// A job that cannot be machined as asked.
    pub fn job(place: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Job { place: place.into(), reason: reason.into() }
    }
    /// An input-file error.
    pub fn input(file: impl Into<PathBuf>, place: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Input { file: file.into(), place: place.into(), reason: reason.into() }
    }
    /// The error, said of `file` where it is about the job read from it: a [`Error::Job`]
    /// becomes an [`Error::Input`] naming the file; any other error is kept.
    pub fn in_file(self, file: impl Into<PathBuf>) -> Self {
        match self {
            Error::Job { place, reason } => Error::input(file, place, reason),
            e => e,
        }
    }
    /// True when the error is the user's input (exit code 2), false for I/O trouble and outputs
    /// that cannot be made.
    pub fn is_user_error(&self) -> bool {
        !matches!(self, Error::Io { .. } | Error::Output { .. })
    }
}

/// The settings a user can give, each by its name in the library (see [`Setting::name`]).
///
/// Each one is checked where its struct is validated: [`crate::model::Cutting::validate`],
/// [`crate::model::Job::validate`], [`crate::model::MeshJob::validate`],
/// [`crate::plan::LinkOptions::validate`], [`crate::strategy::Strategy::validate`],
/// [`crate::sim::SimOptions::validate`], [`crate::io::Overrides::validate`] and
/// [`crate::job::toolseq::SeqOptions::validate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Setting {
    /// `tool.diameter`: the tool diameter, mm.
    ToolDiameter,
    /// `width.stepover`: the width of cut as a fraction of the diameter.
    Stepover,
    /// `width.engagement_deg`: the width of cut as the engagement of a straight cut, degrees.
    Engagement,
    /// `cutting.feed`: the cutting feed, mm/min.
    Feed,
    /// `cutting.rapid_rate`: the rapid rate for time estimates, mm/min.
    RapidRate,
    /// `cutting.max_feed`: the machine's highest cutting feed, mm/min.
    MaxFeed,
    /// `cutting.spindle_rpm`: the spindle speed, rpm.
    SpindleSpeed,
    /// `stepdown`: the largest depth of a level, mm.
    Stepdown,
    /// `floor`: the depth to clear to, mm.
    Floor,
    /// `stock_top`: the top of the stock, mm.
    StockTop,
    /// `part_top`: the top of the part, mm.
    PartTop,
    /// `allowance`: stock to leave on the part's walls, mm.
    Allowance,
    /// `allowance_floor`: stock to leave on floors, mm.
    AllowanceFloor,
    /// `stock_box`: a mesh job's stock box.
    StockBox,
    /// `overrides.depth`: the depth a drawing is cut to, mm.
    Depth,
    /// `overrides.stock_margin`: the stock round an STL part, mm.
    StockMargin,
    /// `overrides.stock_above`: the stock above an STL part's top, mm.
    StockAbove,
    /// `placement.scale`: an STL part's scale.
    PartScale,
    /// `placement.rotate_deg`: an STL part's rotations, degrees.
    PartRotate,
    /// `placement.translate`: an STL part's translation, mm.
    PartTranslate,
    /// `import.chain_tolerance`: how far apart drawing entities may end and still be joined, mm.
    ChainTolerance,
    /// `import.flatten_tolerance`: the chord tolerance of curves a drawing cannot keep exact, mm.
    FlattenTolerance,
    /// `import.svg_px_per_inch`: SVG pixels per inch.
    SvgDpi,
    /// `link.stock_to_leave`: radial stock the roughing leaves for the finishing contour, mm.
    StockToLeave,
    /// `link.ramp_angle_deg`: the ramp and helix angle, degrees.
    RampAngle,
    /// `link.helix_radius_frac` and `link.helix_min_frac`: the helix radii, fractions of the
    /// tool radius.
    HelixRadius,
    /// `link.arc_tol`: the arc-fitting tolerance, mm.
    ArcTolerance,
    /// `link.clearance`: the clearance above the job for travel, mm.
    Clearance,
    /// `link.approach`: the height above material entries start from, mm.
    Approach,
    /// `link.entry_feed_frac` and `link.ramp_feed_frac`: entry feeds as fractions of the feed.
    EntryFeed,
    /// `link.feed_boost`: how far the feed may rise where the tool cuts little.
    FeedBoost,
    /// `adaptive.overshoot_deg`: how far above the reference wall-following may go, degrees.
    Overshoot,
    /// `zigzag.angle_deg`: the zigzag row angle, degrees.
    ZigzagAngle,
    /// `spiral.zeta`: a constant damping of the spiral.
    Zeta,
    /// `spiral.floor`: the least gap between turns, a fraction of the stepover.
    SpiralFloor,
    /// `spiral.start`: where the spiral starts.
    SpiralStart,
    /// `spiral.search_cells`: the work the spiral search may spend simulating.
    SpiralSearch,
    /// `sim.res`: the simulation cell size or sample spacing, mm.
    Resolution,
    /// `sim.engine`: the simulator that proves the program.
    SimEngine,
    /// The other simulation settings (`sim.tol`, `sim.eps`, `sim.ring_delta`,
    /// `sim.sample_step`, `sim.max_cells`).
    Simulation,
    /// `toolseq.ramp_deg`: the largest ramp angle of a tool-sequence program, degrees.
    SeqRampAngle,
    /// `toolseq.clearance`: the clearance plane of tool-sequence programs, mm.
    SeqClearance,
    /// `oscillator.stepover`: the stepover of an oscillator spiral drawn over a shape.
    OscillatorStepover,
    /// The other settings of an oscillator spiral (`oscillator.rtol`, `oscillator.atol`,
    /// `oscillator.max_step`, `oscillator.start_offset`, its damping's bounds).
    Oscillator,
    /// `shape.levels`: the level sets a picture of a shape draws.
    ShapeLevels,
    /// `strategy`: the clearing strategy, by name.
    Strategy,
    /// `post`: the controller dialect, by name.
    Post,
    /// `offset.order`: the order of offset passes, by name.
    OffsetOrder,
    /// `toolseq.decomposition`: how a later tool is confined, by name.
    Decomposition,
}

impl Setting {
    /// Its name in the library: the options struct (or the job's field) and the field.
    pub const fn name(self) -> &'static str {
        match self {
            Setting::ToolDiameter => "tool.diameter",
            Setting::Stepover => "width.stepover",
            Setting::Engagement => "width.engagement_deg",
            Setting::Feed => "cutting.feed",
            Setting::RapidRate => "cutting.rapid_rate",
            Setting::MaxFeed => "cutting.max_feed",
            Setting::SpindleSpeed => "cutting.spindle_rpm",
            Setting::Stepdown => "stepdown",
            Setting::Floor => "floor",
            Setting::StockTop => "stock_top",
            Setting::PartTop => "part_top",
            Setting::Allowance => "allowance",
            Setting::AllowanceFloor => "allowance_floor",
            Setting::StockBox => "stock_box",
            Setting::Depth => "overrides.depth",
            Setting::StockMargin => "overrides.stock_margin",
            Setting::StockAbove => "overrides.stock_above",
            Setting::PartScale => "placement.scale",
            Setting::PartRotate => "placement.rotate_deg",
            Setting::PartTranslate => "placement.translate",
            Setting::ChainTolerance => "import.chain_tolerance",
            Setting::FlattenTolerance => "import.flatten_tolerance",
            Setting::SvgDpi => "import.svg_px_per_inch",
            Setting::StockToLeave => "link.stock_to_leave",
            Setting::RampAngle => "link.ramp_angle_deg",
            Setting::HelixRadius => "link.helix_radius_frac",
            Setting::ArcTolerance => "link.arc_tol",
            Setting::Clearance => "link.clearance",
            Setting::Approach => "link.approach",
            Setting::EntryFeed => "link.entry_feed_frac",
            Setting::FeedBoost => "link.feed_boost",
            Setting::Overshoot => "adaptive.overshoot_deg",
            Setting::ZigzagAngle => "zigzag.angle_deg",
            Setting::Zeta => "spiral.zeta",
            Setting::SpiralFloor => "spiral.floor",
            Setting::SpiralStart => "spiral.start",
            Setting::SpiralSearch => "spiral.search_cells",
            Setting::Resolution => "sim.res",
            Setting::SimEngine => "sim.engine",
            Setting::Simulation => "sim",
            Setting::SeqRampAngle => "toolseq.ramp_deg",
            Setting::SeqClearance => "toolseq.clearance",
            Setting::OscillatorStepover => "oscillator.stepover",
            Setting::Oscillator => "oscillator",
            Setting::ShapeLevels => "shape.levels",
            Setting::Strategy => "strategy",
            Setting::Post => "post",
            Setting::OffsetOrder => "offset.order",
            Setting::Decomposition => "toolseq.decomposition",
        }
    }
}
