//! The `swarf` command: a thin layer over the `swarf` library.

//!
//! Every option maps onto a field of the library's options structs; what an option left out
//! means is the library's default (`LinkOptions::DEFAULT`, `SimOptions::DEFAULT`, …), shown in
//! `--help` from those constants. Bad values are refused by the library, which names the
//! setting; this maps the setting to its flag.

use anyhow::Context;
use clap::builder::PossibleValuesParser;
use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use swarf::io::output::{self, OutputFile};
use swarf::io::{Input, Overrides};
use swarf::job::rough::{RoughOptions, RoughResult, Stage};
use swarf::job::toolseq::{Decomposition, SeqOptions};
use swarf::model::Width;
use swarf::plan::LinkOptions;
use swarf::post::Post;
use swarf::sim::SimEngine;
use swarf::strategy::{OffsetOrder, Strategy};
use swarf::{Error, Setting};

/// swarf: CNC roughing toolpaths you can trust.
#[derive(Parser)]
#[command(name = "swarf", version, about, long_about = None)]
struct Cli {
    /// Log what swarf does to stderr: -v the stages, -vv timings and decisions, -vvv
    /// everything (`RUST_LOG` works too, e.g. `RUST_LOG=swarf=debug`).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Rough a job (case JSON, STL part, DXF or SVG): write G-code, and optionally a report and
    /// pictures.
    Rough(RoughArgs),
    /// Find the cheapest sequence of tools from a tool database for z-level roughing of a 3D
    /// job (paper 3): one program per tool of that sequence, a JSON report of every sequence
    /// costed, and a picture of the stock after each tool.
    Plan(PlanArgs),
    /// Draw an implicit shape file (paper 4: R-function shapes in JSON): its zero set, a few
    /// level sets, and optionally the oscillator spiral from its maximum.
    Shape(ShapeArgs),
    /// Pocket a 5-axis case (a floor and a top as NURBS surfaces, walls, a tilted tool;
    /// paper 2 §2): write the C¹ toolpath as an APT CL file and, with --gcode, as LinuxCNC
    /// G-code for the case's table-tilting A/C machine.
    Five(FiveArgs),
    /// Look at programs (G-code from swarf or any other system) on a job: replay each on swarf's
    /// simulator and write one interactive 3D page (HTML) showing them side by side.
    View(ViewArgs),
    /// Run the built-in example (a pocket with two islands) and write everything into a folder.
    Demo {
        /// Output folder.
        #[arg(default_value = "swarf-demo")]
        out_dir: PathBuf,
        #[command(flatten)]
        opts: CommonOpts,
    },
}

#[derive(Copy, Clone, PartialEq, Eq, ValueEnum)]
enum SimArg {
    /// Heights on a raster of cells.
    Raster,
    /// Sampled signed distance fields (paper 4 §4).
    Sdf,
}

#[derive(Copy, Clone, PartialEq, Eq, ValueEnum)]
enum OrderArg {
    InsideOut,
    OutsideIn,
}

#[derive(Copy, Clone, PartialEq, Eq, ValueEnum)]
enum UnitsArg {
    Mm,
    In,
    Cm,
    M,
}

#[derive(Args, Clone)]
struct PlacementOpts {
    /// Units of a drawing (DXF, SVG) or an STL part read on its own, whatever the file says.
    #[arg(long, value_enum)]
    units: Option<UnitsArg>,
    /// Drawing, or STL part on its own: scale (25.4 for inches; `--units` works too).
    #[arg(long, value_name = "FACTOR", allow_negative_numbers = true)]
    part_scale: Option<f64>,
    /// STL part on its own: rotations about X, Y and Z in degrees, in that order (−90,0,0 turns a
    /// Y-up part Z-up). Without it a part drawn sideways is laid flat on its back; 0,0,0 keeps
    /// it as drawn.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    part_rotate: Option<String>,
    /// STL part on its own: translation after scaling and rotating, mm.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    part_translate: Option<String>,
    /// STL part on its own: the stock box is its bounds grown by this sideways, mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    stock_margin: Option<f64>,
    /// STL part on its own: stock above the part's top, mm (default 0: no facing of a top
    /// nobody asked to face).
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    stock_above: Option<f64>,
}

#[derive(Args, Clone)]
struct CommonOpts {
    /// Clearing strategy: adaptive (engagement held near the reference, paper 1), offset
    /// (contour-parallel), zigzag, medial (C1 circles along the medial axis, paper 2) or spiral
    /// (one oscillator spiral, paper 4).
    #[arg(long, value_parser = PossibleValuesParser::new(Strategy::NAMES))]
    strategy: Option<String>,
    /// Tool diameter, mm (overrides the input).
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    tool_diameter: Option<f64>,
    /// Width of cut as the engagement angle of a straight cut, degrees.
    #[arg(long, value_name = "DEG", conflicts_with = "stepover", allow_negative_numbers = true)]
    engagement: Option<f64>,
    /// Width of cut as a fraction of the tool diameter, in (0, 1].
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true)]
    stepover: Option<f64>,
    /// Largest depth per level, mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    stepdown: Option<f64>,
    /// Depth below the stock top for drawings (DXF, SVG), mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    depth: Option<f64>,
    /// Cutting feed, mm/min.
    #[arg(long, value_name = "MM_PER_MIN", allow_negative_numbers = true)]
    feed: Option<f64>,
    /// The machine's highest cutting feed, mm/min: the feed raised where the tool cuts little
    /// (--feed-boost) stays under it.
    #[arg(long, value_name = "MM_PER_MIN", allow_negative_numbers = true)]
    max_feed: Option<f64>,
    /// Spindle speed, rpm.
    #[arg(long, value_name = "RPM", allow_negative_numbers = true)]
    spindle: Option<f64>,
    /// Controller dialect.
    #[arg(long, value_parser = PossibleValuesParser::new(Post::NAMES))]
    post: Option<String>,
    /// Conventional instead of climb milling.
    #[arg(long)]
    conventional: bool,
    /// Order of offset passes.
    #[arg(long, value_enum)]
    order: Option<OrderArg>,
    /// Zigzag row angle, degrees.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    angle: Option<f64>,
    /// Radial stock the roughing leaves for the finishing contour, mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    stock_to_leave: Option<f64>,
    /// Add a finishing contour at every level.
    #[arg(long)]
    finish: bool,
    /// Ramp and helix angle, degrees.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    ramp_angle: Option<f64>,
    /// Adaptive (and the adaptive passes round a spiral's islands): engagement above the
    /// reference that wall-following may reach before the tool turns back to constant
    /// engagement (paper 1 §4.4), degrees.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    overshoot: Option<f64>,
    /// Adaptive: raise the feed where the engagement is low, by up to this factor and never
    /// above --max-feed (chip-thinning compensation 1/sin θ, which holds the programmed chip
    /// thickness, smoothed over a tool diameter; paper 1 §5). Medial: the feed of the cut-back
    /// returns through cleared space (paper 2, conclusion). 1 = off.
    #[arg(long, value_name = "FACTOR", allow_negative_numbers = true)]
    feed_boost: Option<f64>,
    /// Links through cleared space as feed moves (G1 at the cutting feed times the feed boost)
    /// instead of rapids at depth: for controls whose G0 is not a straight line.
    #[arg(long)]
    feed_links: bool,
    /// Z-level jobs: cut each level over the whole part before the next, instead of region by
    /// region through the levels.
    #[arg(long)]
    level_by_level: bool,
    /// Medial: follow every circle all the way round (paper 2 Fig. 1c) instead of returning to
    /// the next circle on a cut-back turn (Fig. 2c, the default).
    #[arg(long)]
    full_circles: bool,
    /// Spiral: a constant damping ζ (paper 4 eq. 6; the spiral grows by e^(2πζ) per turn on a
    /// disk) instead of ζ chosen per level to keep the stepover and the engagement.
    #[arg(long, value_name = "ZETA", allow_negative_numbers = true, conflicts_with = "optimise")]
    zeta: Option<f64>,
    /// Spiral: start at this point instead of the maximum of the pocket's implicit function.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true, conflicts_with = "optimise")]
    spiral_start: Option<String>,
    /// Spiral, ζ per level: the least gap between turns where they curve tightly, as a
    /// fraction of the stepover (lower holds the engagement better in tight turns, and is
    /// slower). Without it, floors from 0.5 down are simulated and the fastest within the
    /// engagement bound is kept.
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true, conflicts_with_all = ["optimise", "zeta"])]
    spiral_floor: Option<f64>,
    /// Spiral: choose the start point too (the maximum of the pocket's implicit function and
    /// four points round it), simulating candidates and keeping the fastest that clears the
    /// pocket within the engagement bound (paper 4 §4).
    #[arg(long)]
    optimise: bool,
    /// Arc-fitting tolerance, mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    arc_tolerance: Option<f64>,
    /// Clearance above the top of the job for travel, mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    clearance: Option<f64>,
    /// Simulation cell size, mm (default: tool diameter / 100 within [0.02, 0.1]); with
    /// `--sim sdf`, the distance fields' sample spacing.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    res: Option<f64>,
    /// Simulator for the report: `raster` (cell heights, exact engagement from the cleared
    /// geometry) or `sdf` (sampled signed distance fields per slab, engagement by root finding
    /// on the field; 2.5D jobs only). Planning always uses the raster.
    #[arg(long, value_enum)]
    sim: Option<SimArg>,
    /// Skip the simulation (no engagement, gouge or rest figures).
    #[arg(long)]
    no_simulate: bool,
    /// Measure the exact engagement at every sample of the simulation (slower) instead of
    /// every R/6 along a move and wherever the pixel reading leaves it in doubt.
    #[arg(long, conflicts_with = "no_simulate")]
    exact_every_sample: bool,
    /// SVG pixels per inch (old Inkscape files use 90).
    #[arg(long, value_name = "PX", allow_negative_numbers = true)]
    svg_dpi: Option<f64>,
    /// Tolerance for joining loose drawing entities into contours, mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    chain_tolerance: Option<f64>,
    /// Drawings without STOCK or PART layers: what to cut. auto: outlines holding holes are
    /// parts (holes and outside cut), a rectangle round everything is the stock's edge, lone
    /// outlines are pockets; all: parts, holes and outside; outside: parts cut out, holes left;
    /// holes: only the holes; pockets: every outline a pocket wall, nested ones islands.
    #[arg(long, value_parser = PossibleValuesParser::new(swarf::io::drawing::Cut::NAMES))]
    cut: Option<String>,
    /// Drawings: leave out contours that stay open after chaining (each is listed) and cut the
    /// rest.
    #[arg(long)]
    skip_open: bool,
    /// Drawings: read only these layers (DXF) or groups (SVG, by label or id), comma-separated.
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    layers: Vec<String>,
    /// Drawings: leave out these layers or groups, comma-separated.
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    ignore_layers: Vec<String>,
    #[command(flatten)]
    place: PlacementOpts,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args)]
struct RoughArgs {
    /// Input: a case (.json, 2.5D or 3D), an STL part, a DXF or an SVG drawing.
    input: PathBuf,
    /// G-code output (default: the input's name with .ngc, in the current folder).
    #[arg(short, long, value_name = "OUT.ngc")]
    output: Option<PathBuf>,
    /// Report (JSON).
    #[arg(long, value_name = "OUT.json")]
    report: Option<PathBuf>,
    /// Picture of the path coloured by engagement (.svg or .png; both when the name has no
    /// extension).
    #[arg(long, value_name = "OUT.svg|OUT.png")]
    plot: Option<PathBuf>,
    /// Engagement samples along the path (CSV: cut length, x, y, z, exact and pixel
    /// engagement, kind, entry bore, move index).
    #[arg(long, value_name = "OUT.csv")]
    samples: Option<PathBuf>,
    /// Interactive 3D view of the program: one self-contained HTML page to open in a browser
    /// (playback over the stock, the engagement chart, filters by level).
    #[arg(long, value_name = "OUT.html")]
    html: Option<PathBuf>,
    #[command(flatten)]
    opts: CommonOpts,
}

#[derive(Args)]
struct ViewArgs {
    /// The programs (G-code: LinuxCNC, GRBL or FreeCAD's posts); each is replayed on a fresh
    /// stock of the job, and the page shows them side by side.
    #[arg(required = true, value_name = "PROGRAM.ngc")]
    programs: Vec<PathBuf>,
    /// The job the programs cut: a case (.json, 2.5D or 3D), an STL part, a DXF or an SVG
    /// drawing.
    #[arg(long, value_name = "CASE")]
    case: PathBuf,
    /// The page (HTML).
    #[arg(short, long, value_name = "OUT.html", default_value = "view.html")]
    output: PathBuf,
    /// The tool's diameter, mm (default: the job's).
    #[arg(long, value_name = "MM")]
    tool_diameter: Option<f64>,
    /// A program that changes tools (M6): the diameter of tool N, mm (repeat for each tool;
    /// a tool not named is the job's). Each tool's moves are replayed on what the ones before
    /// it left, a tool per colour.
    #[arg(long = "tool", value_name = "N=MM")]
    tools: Vec<String>,
    /// Simulation cell size, mm (default: a hundredth of the tool, 0.02 to 0.1 mm).
    #[arg(long, value_name = "MM")]
    res: Option<f64>,
    #[command(flatten)]
    place: PlacementOpts,
    /// Print nothing.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Copy, Clone, PartialEq, Eq, ValueEnum)]
enum DecompositionArg {
    /// Algorithm 4: each tool's own path, trimmed to where earlier tools left material.
    Trim,
    /// Algorithm 3: a new path over each rest region.
    Regions,
}

#[derive(Args)]
struct PlanArgs {
    /// Input: a 3D case (.json with part_stl) or an STL part.
    input: PathBuf,
    /// Tool database (JSON: machine and tools, as paper 3's Table 1).
    #[arg(long, value_name = "TOOLS.json")]
    tools: PathBuf,
    /// Folder for the programs (01_T1_D80.ngc, ... in cutting order) and the pictures.
    #[arg(long, value_name = "DIR", default_value = "swarf-plan")]
    output_dir: PathBuf,
    /// Report (JSON): the best sequence and every sequence costed (default: DIR/plan.json).
    #[arg(long, value_name = "PLAN.json")]
    report: Option<PathBuf>,
    /// How later tools are confined to the rest material.
    #[arg(long, value_enum)]
    decomposition: Option<DecompositionArg>,
    /// Cost every candidate sequence (no bound).
    #[arg(long)]
    exhaustive: bool,
    /// Controller dialect.
    #[arg(long, value_parser = PossibleValuesParser::new(Post::NAMES))]
    post: Option<String>,
    /// Largest ramp angle of an entry, degrees.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    ramp_angle: Option<f64>,
    /// Clearance above the top of the job for travel, mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    clearance: Option<f64>,
    /// No pictures of the rest material.
    #[arg(long)]
    no_pictures: bool,
    /// Skip the replay of the chosen programs on the simulator (no gouge, rapid collision or
    /// rest figures per program in the report, no pictures).
    #[arg(long)]
    no_simulate: bool,
    /// Rows of the table printed (the cheapest sequences).
    #[arg(long, value_name = "N", default_value_t = 15)]
    rows: usize,
    /// Interactive 3D view of the programs, a tool per colour, each replayed on what the ones
    /// before it left: one self-contained HTML page.
    #[arg(long, value_name = "OUT.html")]
    html: Option<PathBuf>,
    #[command(flatten)]
    place: PlacementOpts,
    /// Print nothing.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args)]
struct ShapeArgs {
    /// The shape file (JSON).
    input: PathBuf,
    /// Output picture (.svg, or .png).
    #[arg(short, long, default_value = "shape.svg")]
    output: PathBuf,
    /// Level sets drawn between 0 and the maximum.
    #[arg(long, default_value_t = 6)]
    levels: usize,
    /// Also draw the spiral with this stepover (same unit as the file), ending on the level a
    /// tenth of the stepover inside.
    #[arg(long)]
    spiral: Option<f64>,
    /// Print nothing.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args)]
struct FiveArgs {
    /// The 5-axis case (JSON, "kind": "fiveaxis_pocket").
    input: PathBuf,
    /// Output CL file.
    #[arg(short, long, default_value = "five.cl")]
    output: PathBuf,
    /// Also write G-code for the case's machine (xyzac-trt, tool-centre-point form) here.
    #[arg(long)]
    gcode: Option<PathBuf>,
    /// The back of each rounded shape as a fraction of its front's radius (1: full circles).
    #[arg(long, default_value_t = 0.5)]
    back: f64,
    /// Also draw the path: the domain before and after the offset, the path on the floor and
    /// the orientation field (.svg, or .png).
    #[arg(long)]
    picture: Option<PathBuf>,
    /// Interactive 3D view of the path with the tool axis, over the floor and the walls: one
    /// self-contained HTML page.
    #[arg(long, value_name = "OUT.html")]
    html: Option<PathBuf>,
    /// Print nothing.
    #[arg(long, short)]
    quiet: bool,
}

/// An error that is the user's fault (exit 2) or not (exit 1).
struct Failure {
    user: bool,
    msg: String,
}

impl From<swarf::Error> for Failure {
    fn from(e: swarf::Error) -> Self {
        let user = e.is_user_error();
        let msg = match &e {
            // (the library names the setting; the user knows it by its flag)
            Error::Setting { setting, reason } => match flag(*setting) {
                Some(f) => format!("{f}: {reason}"),
                None => e.to_string(),
            },
            _ => e.to_string(),
        };
        Failure { user, msg }
    }
}

/// The flag that sets a setting, where one does.
fn flag(s: Setting) -> Option<&'static str> {
    Some(match s {
        Setting::ToolDiameter => "--tool-diameter",
        Setting::Stepover => "--stepover",
        Setting::Engagement => "--engagement",
        Setting::Feed => "--feed",
        Setting::MaxFeed => "--max-feed",
        Setting::SpindleSpeed => "--spindle",
        Setting::Stepdown => "--stepdown",
        Setting::Depth => "--depth",
        Setting::StockMargin => "--stock-margin",
        Setting::StockAbove => "--stock-above",
        Setting::PartScale => "--part-scale",
        Setting::PartRotate => "--part-rotate",
        Setting::PartTranslate => "--part-translate",
        Setting::ChainTolerance => "--chain-tolerance",
        Setting::SvgDpi => "--svg-dpi",
        Setting::StockToLeave => "--stock-to-leave",
        Setting::RampAngle | Setting::SeqRampAngle => "--ramp-angle",
        Setting::ArcTolerance => "--arc-tolerance",
        Setting::Clearance | Setting::SeqClearance => "--clearance",
        Setting::FeedBoost => "--feed-boost",
        Setting::Overshoot => "--overshoot",
        Setting::ZigzagAngle => "--angle",
        Setting::Zeta => "--zeta",
        Setting::SpiralFloor => "--spiral-floor",
        Setting::SpiralStart => "--spiral-start",
        Setting::Resolution => "--res",
        Setting::SimEngine => "--sim",
        Setting::OscillatorStepover => "--spiral",
        Setting::ShapeLevels => "--levels",
        Setting::Strategy => "--strategy",
        Setting::Post => "--post",
        Setting::OffsetOrder => "--order",
        Setting::Decomposition => "--decomposition",
        Setting::RapidRate
        | Setting::Floor
        | Setting::StockTop
        | Setting::PartTop
        | Setting::Allowance
        | Setting::AllowanceFloor
        | Setting::StockBox
        | Setting::FlattenTolerance
        | Setting::HelixRadius
        | Setting::Approach
        | Setting::EntryFeed
        | Setting::Simulation
        | Setting::SpiralSearch
        | Setting::Oscillator => return None,
    })
}

/// What the library does when an option is left out, for `--help`: (subcommand, argument id,
/// value), read from the library's defaults.
fn library_defaults() -> Vec<(&'static str, &'static str, String)> {
    let num = |v: f64| swarf::post::num(v, 6);
    let l = LinkOptions::DEFAULT;
    let o = Overrides::DEFAULT;
    let seq = SeqOptions::DEFAULT;
    let mut v = Vec::new();
    for cmd in ["rough", "demo"] {
        v.extend([
            (cmd, "strategy", Strategy::DEFAULT.name().to_string()),
            (cmd, "tool_diameter", format!("{} for drawings and STL parts", num(swarf::model::Tool::DEFAULT.diameter))),
            (cmd, "stepover", num(swarf::model::Width::DEFAULT.stepover()) + " when the input names none"),
            (cmd, "depth", num(Overrides::DEFAULT_DEPTH)),
            (
                cmd,
                "stepdown",
                format!(
                    "{} × the tool diameter for STL parts; drawings are cut in one level",
                    num(swarf::model::MeshJob::DEFAULT_STEPDOWN_FRACTION)
                ),
            ),
            (cmd, "feed", format!("{} for drawings and STL parts", num(swarf::model::Cutting::DEFAULT.feed))),
            (cmd, "spindle", format!("{} for drawings and STL parts", num(swarf::model::Cutting::DEFAULT.spindle_rpm))),
            (cmd, "max_feed", "the rapid rate".to_string()),
            (cmd, "post", Post::DEFAULT.name().to_string()),
            (cmd, "order", swarf::strategy::OffsetOptions::DEFAULT.order.name().to_string()),
            (cmd, "angle", num(swarf::strategy::ZigzagOptions::DEFAULT.angle_deg)),
            (cmd, "stock_to_leave", num(l.stock_to_leave)),
            (cmd, "ramp_angle", num(l.ramp_angle_deg)),
            (cmd, "overshoot", num(swarf::strategy::AdaptiveOptions::DEFAULT.overshoot_deg)),
            (cmd, "feed_boost", num(l.feed_boost)),
            (cmd, "arc_tolerance", num(l.arc_tol)),
            (cmd, "clearance", num(l.clearance)),
            (cmd, "sim", SimEngine::default().name().to_string()),
            (cmd, "svg_dpi", "96 (90 for files Inkscape before 0.92 wrote)".to_string()),
            (cmd, "chain_tolerance", num(o.import.chain_tolerance)),
            (cmd, "stock_margin", num(o.stock_margin)),
            (cmd, "stock_above", num(o.stock_above)),
        ]);
    }
    v.extend([
        ("plan", "decomposition", seq.decomposition.name().to_string()),
        ("plan", "post", Post::DEFAULT.name().to_string()),
        ("plan", "ramp_angle", num(seq.ramp_deg)),
        ("plan", "clearance", num(seq.clearance)),
        ("plan", "stock_margin", num(o.stock_margin)),
        ("plan", "stock_above", num(o.stock_above)),
    ]);
    v
}

/// The command with the library's defaults in the help of the options that have one.
fn command() -> clap::Command {
    let mut cmd = Cli::command();
    for (sub, id, value) in library_defaults() {
        cmd = cmd.mut_subcommand(sub, |c| {
            c.mut_arg(id, |a| {
                let help = a.get_help().map(|h| h.to_string()).unwrap_or_default();
                let a = a.help(format!("{help} [default: {value}]"));
                match a.get_long_help().map(|h| h.to_string()) {
                    Some(long) => a.long_help(format!("{long}\n\n[default: {value}]")),
                    None => a,
                }
            })
        });
    }
    cmd
}

impl From<anyhow::Error> for Failure {
    fn from(e: anyhow::Error) -> Self {
        Failure { user: false, msg: format!("{e:#}") }
    }
}

/// SIGINT, SIGTERM and SIGHUP end the run with no temporary file left behind and the outputs
/// either all written or none (`output::interrupt` waits for a renaming in progress), with the
/// shell's exit status for a signal, 128 + its number.
fn stop_cleanly_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            output::interrupt();
            eprintln!("swarf: stopped by signal {sig}");
            std::process::exit(128 + sig);
        }
    });
}

fn main() -> ExitCode {
    let cli = match command().try_get_matches().and_then(|m| Cli::from_arg_matches(&m)) {
        Ok(c) => c,
        Err(e) => {
            if !e.use_stderr() {
                // --help, --version
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            // one line: the first line of clap's message, without its "error: " prefix
            let text = e.to_string();
            let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("bad arguments");
            eprintln!("swarf: {} (see swarf --help)", first.trim_start_matches("error: "));
            return ExitCode::from(2);
        }
    };
    let level = match cli.verbose {
        0 => log::LevelFilter::Warn,
        1 => log::LevelFilter::Info,
        2 => log::LevelFilter::Debug,
        _ => log::LevelFilter::Trace,
    };
    // (swarf's own messages at the level asked for; the libraries it uses only when they fail,
    // unless RUST_LOG says otherwise)
    let mut logger = env_logger::Builder::new();
    logger
        .filter_level(log::LevelFilter::Error)
        .filter_module("swarf", level)
        .filter_module("swarf_import", level)
        .parse_default_env()
        .format_target(false);
    if cli.verbose == 0 {
        // (a user's warnings read like the rest of swarf's: no time stamp, no level tag)
        logger.format(|buf, rec| {
            use std::io::Write as _;
            let what = if rec.level() == log::Level::Error { "error" } else { "warning" };
            writeln!(buf, "swarf: {what}: {}", rec.args())
        });
    }
    logger.init();
    stop_cleanly_on_signals();
    let res = match cli.cmd {
        Cmd::Rough(a) => rough(a),
        Cmd::Plan(a) => plan(a),
        Cmd::Five(a) => five(a),
        Cmd::Shape(a) => shape(a),
        Cmd::View(a) => view(a),
        Cmd::Demo { out_dir, opts } => demo(&out_dir, &opts),
    };
    match res {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            let first = f.msg.lines().next().unwrap_or("error");
            eprintln!("swarf: {first}");
            ExitCode::from(if f.user { 2 } else { 1 })
        }
    }
}

/// The overrides of the input the options give.
fn overrides(o: &CommonOpts) -> Result<Overrides, Failure> {
    let mut ov = Overrides {
        tool_diameter: o.tool_diameter,
        width: match (o.engagement, o.stepover) {
            (Some(t), _) => Some(Width::EngagementDeg(t)),
            (None, Some(s)) => Some(Width::Stepover(s)),
            _ => None,
        },
        stepdown: o.stepdown,
        depth: o.depth,
        feed: o.feed,
        max_feed: o.max_feed,
        spindle_rpm: o.spindle,
        ..placement(&o.place)?
    };
    if let Some(d) = o.svg_dpi {
        ov.import.svg_px_per_inch = Some(d);
    }
    if let Some(t) = o.chain_tolerance {
        ov.import.chain_tolerance = t;
    }
    if let Some(c) = &o.cut {
        ov.cut = swarf::io::drawing::Cut::parse(c).unwrap_or_default();
    }
    ov.import.skip_open = o.skip_open;
    ov.import.layers = o.layers.clone();
    ov.import.ignore_layers = o.ignore_layers.clone();
    Ok(ov)
}

/// The overrides of units and of an STL part's placement.
fn placement(o: &PlacementOpts) -> Result<Overrides, Failure> {
    let mut ov = Overrides::DEFAULT;
    ov.import.units = o.units.map(|u| match u {
        UnitsArg::Mm => swarf::swarf_import::Units::Millimetre,
        UnitsArg::In => swarf::swarf_import::Units::Inch,
        UnitsArg::Cm => swarf::swarf_import::Units::Centimetre,
        UnitsArg::M => swarf::swarf_import::Units::Metre,
    });
    if let Some(r) = &o.part_rotate {
        ov.placement.rotate_deg = triple(r, Setting::PartRotate)?;
        // (a rotation given, even 0,0,0, keeps the part as the user turned it)
        ov.lay_flat = false;
    }
    if let Some(t) = &o.part_translate {
        ov.placement.translate = swarf::geom::DVec3::from_array(triple(t, Setting::PartTranslate)?);
    }
    if let Some(sc) = o.part_scale {
        ov.placement.scale = sc;
    }
    if let Some(m) = o.stock_margin {
        ov.stock_margin = m;
    }
    if let Some(m) = o.stock_above {
        ov.stock_above = m;
    }
    Ok(ov)
}

/// Parses `X,Y,Z`.
fn triple(t: &str, setting: Setting) -> Result<[f64; 3], Failure> {
    let parts: Vec<Option<f64>> = t.split(',').map(|x| x.trim().parse::<f64>().ok()).collect();
    match parts.as_slice() {
        [Some(a), Some(b), Some(c)] => Ok([*a, *b, *c]),
        _ => Err(Error::setting(setting, format!("{t:?}: expected three numbers X,Y,Z")).into()),
    }
}

/// Parses `X,Y` (for `--spiral-start`).
fn pair(t: &str) -> Result<swarf::geom::DVec2, Failure> {
    let v: Vec<Option<f64>> = t.split(',').map(|x| x.trim().parse::<f64>().ok()).collect();
    match v.as_slice() {
        [Some(x), Some(y)] => Ok(swarf::geom::DVec2::new(*x, *y)),
        _ => Err(Error::setting(Setting::SpiralStart, format!("{t:?}: expected two numbers X,Y (mm)")).into()),
    }
}

/// The run's settings the flags give ([`swarf::Settings`], which holds the defaults and the
/// checks).
fn settings(o: &CommonOpts) -> Result<swarf::Settings, Failure> {
    Ok(swarf::Settings {
        strategy: o.strategy.clone(),
        post: o.post.clone(),
        conventional: o.conventional,
        order: o.order.map(|x| {
            match x {
                OrderArg::InsideOut => OffsetOrder::InsideOut,
                OrderArg::OutsideIn => OffsetOrder::OutsideIn,
            }
            .name()
            .to_string()
        }),
        angle: o.angle,
        stock_to_leave: o.stock_to_leave,
        finish: o.finish,
        ramp_angle: o.ramp_angle,
        overshoot: o.overshoot,
        feed_boost: o.feed_boost,
        feed_links: o.feed_links,
        level_by_level: o.level_by_level,
        full_circles: o.full_circles,
        zeta: o.zeta,
        spiral_start: o.spiral_start.as_deref().map(pair).transpose()?,
        spiral_floor: o.spiral_floor,
        optimise: o.optimise,
        arc_tolerance: o.arc_tolerance,
        clearance: o.clearance,
        res: o.res,
        sim: o.sim.map(|x| match x {
            SimArg::Raster => SimEngine::Raster.name().to_string(),
            SimArg::Sdf => SimEngine::Sdf.name().to_string(),
        }),
        no_simulate: o.no_simulate,
        exact_every_sample: o.exact_every_sample,
        ..swarf::Settings::default()
    })
}

/// The options of `rough` the flags give, on top of the library's defaults.
fn options(o: &CommonOpts, input_name: String) -> Result<RoughOptions, Failure> {
    Ok(settings(o)?.rough_options(input_name)?)
}

fn run(job: &swarf::model::Job, opts: &RoughOptions, quiet: bool) -> Result<RoughResult, Failure> {
    with_bar(quiet, |p| swarf::job::rough::rough(job, opts, p))
}

/// Runs `f` with a progress bar on a terminal.
fn with_bar(
    quiet: bool,
    f: impl FnOnce(&mut dyn FnMut(Stage, f64)) -> swarf::Result<RoughResult>,
) -> Result<RoughResult, Failure> {
    let show = !quiet && std::io::stderr().is_terminal();
    let bar = if show { ProgressBar::new(1000) } else { ProgressBar::hidden() };
    bar.set_style(
        ProgressStyle::with_template("{msg:>10} [{bar:40}] {percent:>3}%")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let res = f(&mut |stage, f| {
        bar.set_message(match stage {
            Stage::Plan => "planning",
            Stage::Simulate => "simulating",
        });
        bar.set_position((f * 1000.0) as u64);
    });
    bar.finish_and_clear();
    Ok(res?)
}

struct Outputs {
    gcode: PathBuf,
    report: Option<PathBuf>,
    samples: Option<PathBuf>,
    plot_svg: Option<PathBuf>,
    plot_png: Option<PathBuf>,
    html: Option<PathBuf>,
    /// The files the run read: no output may replace one.
    inputs: Vec<PathBuf>,
}

impl Outputs {
    fn paths(&self) -> Vec<&Path> {
        let opt = [&self.report, &self.samples, &self.plot_svg, &self.plot_png, &self.html];
        std::iter::once(self.gcode.as_path()).chain(opt.into_iter().flatten().map(PathBuf::as_path)).collect()
    }

    fn inputs(&self) -> Vec<&Path> {
        self.inputs.iter().map(PathBuf::as_path).collect()
    }
}

/// What the picture draws under the path.
struct Scene {
    part: swarf::geom::Area,
    stock: swarf::geom::Area,
    fixtures: swarf::geom::Area,
    /// A 3D job's levels with the part's shadow at each.
    levels: Vec<swarf::plot::Level>,
}

impl Scene {
    fn of(job: &swarf::model::Job) -> Scene {
        Scene { part: job.part.clone(), stock: job.stock.clone(), fixtures: job.fixtures.clone(), levels: Vec::new() }
    }

    fn of_mesh(job: &swarf::model::MeshJob, levels: &[f64]) -> Scene {
        let levels = levels.iter().zip(job.shadows(levels)).map(|(&z, part)| swarf::plot::Level { z, part }).collect();
        Scene { part: job.outline(), stock: job.stock_area(), fixtures: swarf::geom::Area::empty(), levels }
    }
}

/// `scene` is drawn under the path, and only asked for when there is a picture to draw.
/// `page` is the program's viewer, only asked for when there is a page to write.
fn write_outputs(
    scene: impl FnOnce() -> Scene,
    page: impl FnOnce() -> swarf::Result<swarf::view::Scene>,
    res: &RoughResult,
    out: &Outputs,
    extra: Vec<OutputFile>,
) -> Result<(), Failure> {
    // render everything first, then write: no output on failure
    let mut files = vec![OutputFile::new(&out.gcode, res.gcode.clone())];
    if let Some(p) = &out.report {
        let json =
            serde_json::to_string_pretty(&res.report).map_err(|e| Failure { user: false, msg: e.to_string() })?;
        files.push(OutputFile::new(p, json + "\n"));
    }
    if let Some(p) = &out.samples {
        let Some(replay) = &res.replay else {
            return Err(Failure {
                user: true,
                msg: "--samples: the samples need the simulation (drop --no-simulate)".into(),
            });
        };
        let mut csv = String::from("cut_length_mm,x,y,z,tea_deg,tea_pixel_deg,kind,bore,move\n");
        for sm in &replay.samples {
            let kind = match sm.kind {
                swarf::sim::SampleKind::Lateral => "lateral",
                swarf::sim::SampleKind::Descending => "descending",
                swarf::sim::SampleKind::Plunge => "plunge",
            };
            csv.push_str(&format!(
                "{:.4},{:.4},{:.4},{:.4},{:.2},{:.2},{},{},{}\n",
                sm.s,
                sm.at.x,
                sm.at.y,
                sm.at.z,
                sm.tea,
                sm.tea_pixel,
                kind,
                u8::from(sm.bore),
                sm.mi
            ));
        }
        files.push(OutputFile::new(p, csv));
    }
    if out.plot_svg.is_some() || out.plot_png.is_some() {
        let Some(replay) = &res.replay else {
            return Err(Failure {
                user: true,
                msg: "--plot: the picture needs the simulation (drop --no-simulate)".into(),
            });
        };
        let scene = scene();
        let fig = swarf::plot::Figure {
            title: format!(
                "{} - {} - D{} - ref {:.0} deg - max {:.0} deg, p95 {:.0} deg - {:.2} min",
                res.report.input,
                res.report.strategy,
                res.report.tool_diameter_mm,
                res.report.engagement_ref_deg,
                res.report.engagement_deg.max,
                res.report.engagement_deg.p95,
                res.report.time_min
            ),
            part: &scene.part,
            stock: &scene.stock,
            fixtures: &scene.fixtures,
            toolpath: &res.toolpath,
            replay,
            ref_deg: res.report.engagement_ref_deg,
            levels: &scene.levels,
        };
        let svg = swarf::plot::svg(&fig);
        if let Some(p) = &out.plot_png {
            files.push(OutputFile::new(p, swarf::plot::png(&svg)?));
        }
        if let Some(p) = &out.plot_svg {
            files.push(OutputFile::new(p, svg));
        }
    }
    if let Some(p) = &out.html {
        files.push(OutputFile::new(p, page()?.html()));
    }
    files.extend(extra);
    output::commit(&files, &out.inputs())?;
    Ok(())
}

fn summary(r: &swarf::report::Report) -> String {
    if !r.simulated {
        return format!(
            "{} {}: {:.0} mm cut, {:.2} min, {} plunges, not simulated, planned in {:.2} s",
            r.input, r.strategy, r.cut_length_mm, r.time_min, r.plunges, r.total_s
        );
    }
    // (3D: the terraces z-level roughing leaves by design, and what the tool could have cut)
    let terraces = if r.rest_terrace_area_mm2 > 0.0 {
        format!(
            " ({:.2}% terraces, {:.2}% beyond them)",
            (r.rest_fraction - r.rest_beyond_terraces_fraction) * 100.0,
            r.rest_beyond_terraces_fraction * 100.0
        )
    } else {
        String::new()
    };
    format!(
        "{} {}: {:.0} mm cut, {:.2} min ({:.0}% efficient), engagement max {:.1} p95 {:.1} deg, {} plunges, {} gouges, {} rapid collisions, rest {:.2}%{terraces}, {:.2} s (planned in {:.2} s, proven in {:.2} s)",
        r.input,
        r.strategy,
        r.cut_length_mm,
        r.time_min,
        r.efficiency * 100.0,
        r.engagement_deg.max,
        r.engagement_deg.p95,
        r.plunges,
        r.gouges,
        r.rapid_collisions,
        r.rest_fraction * 100.0,
        r.total_s,
        r.compute_s,
        r.simulate_s
    )
}

fn rough(a: RoughArgs) -> Result<(), Failure> {
    let (input, reading) = swarf::io::read_input(&a.input, &overrides(&a.opts)?)?;
    let name = a.input.file_name().and_then(|s| s.to_str()).unwrap_or("input").to_string();
    let opts = options(&a.opts, name)?;
    let stem = match &input {
        Input::Flat(j) => j.name.clone(),
        Input::Mesh(j) => j.name.clone(),
    };
    let gcode = a.output.clone().unwrap_or_else(|| PathBuf::from(format!("{stem}.ngc")));
    let (plot_svg, plot_png) = match &a.plot {
        None => (None, None),
        Some(p) => match p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("svg") => (Some(p.clone()), None),
            Some("png") => (None, Some(p.clone())),
            _ => (Some(p.with_extension("svg")), Some(p.with_extension("png"))),
        },
    };
    let out = Outputs {
        gcode,
        report: a.report.clone(),
        samples: a.samples.clone(),
        plot_svg,
        plot_png,
        html: a.html.clone(),
        inputs: reading.files.clone(),
    };
    // (refused before the work, not after it)
    output::check(&out.paths(), &out.inputs())?;
    if !a.opts.quiet {
        eprintln!("{}", reading.line(&input));
        for w in &reading.warnings {
            eprintln!("swarf: warning: {w}");
        }
    }
    // (a job that cannot be planned is said of its file)
    let res = match &input {
        Input::Flat(job) => {
            with_bar(a.opts.quiet, |p| swarf::job::rough::rough(job, &opts, p).map_err(|e| e.in_file(&a.input)))?
        }
        Input::Mesh(job) => {
            with_bar(a.opts.quiet, |p| swarf::job::zlevel::rough(job, &opts, p).map_err(|e| e.in_file(&a.input)))?
        }
    };
    let scene = || match &input {
        Input::Flat(job) => Scene::of(job),
        Input::Mesh(job) => Scene::of_mesh(job, &res.report.levels),
    };
    let page = || match &input {
        Input::Flat(job) => swarf::view::of_rough(job, &res, &opts.sim),
        Input::Mesh(job) => swarf::view::of_mesh_rough(job, &res, &opts.sim),
    };
    write_outputs(scene, page, &res, &out, Vec::new())?;
    if !a.opts.quiet {
        eprintln!("{}", summary(&res.report));
    }
    Ok(())
}

fn demo(dir: &Path, o: &CommonOpts) -> Result<(), Failure> {
    let mut job = swarf::io::example_job();
    let ov = overrides(o)?;
    ov.validate()?;
    ov.apply_to_job(&mut job);
    job.validate()?;
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create the folder", dir.display()))?;
    let opts = options(o, "demo_pocket (built-in)".into())?;
    let out = Outputs {
        gcode: dir.join("demo.ngc"),
        report: Some(dir.join("demo.report.json")),
        samples: None,
        plot_svg: Some(dir.join("demo.svg")),
        plot_png: Some(dir.join("demo.png")),
        html: Some(dir.join("demo.html")),
        inputs: Vec::new(),
    };
    let case = OutputFile::new(dir.join("demo_pocket.json"), swarf::io::EXAMPLE_CASE);
    // (refused before the work, as rough's)
    output::check(&[out.paths(), vec![case.path.as_path()]].concat(), &[])?;
    let res = run(&job, &opts, o.quiet)?;
    write_outputs(|| Scene::of(&job), || swarf::view::of_rough(&job, &res, &opts.sim), &res, &out, vec![case])?;
    if !o.quiet {
        eprintln!("{}", summary(&res.report));
        eprintln!(
            "wrote {}/demo.ngc, demo.report.json, demo.svg, demo.png, the 3D view demo.html and the case demo_pocket.json",
            dir.display()
        );
    }
    Ok(())
}

fn plan(a: PlanArgs) -> Result<(), Failure> {
    let (input, reading) = swarf::io::read_input(&a.input, &placement(&a.place)?)?;
    let Input::Mesh(job) = input else {
        return Err(
            swarf::Error::input(&a.input, "file", "plan needs a 3D job: a case with part_stl, or an STL part").into()
        );
    };
    let db = swarf::model::tooldb::ToolDb::read(&a.tools)?;
    let mut inputs: Vec<&Path> = reading.files.iter().map(PathBuf::as_path).collect();
    inputs.push(&a.tools);
    let report_path = a.report.clone().unwrap_or_else(|| a.output_dir.join("plan.json"));
    // (the report and the page refused before the work; the programs, named after the plan,
    // when written)
    let early: Vec<&Path> = std::iter::once(report_path.as_path()).chain(a.html.as_deref()).collect();
    output::check(&early, &inputs)?;
    let opts = swarf::Settings {
        decomposition: a.decomposition.map(|d| {
            match d {
                DecompositionArg::Trim => Decomposition::Trim,
                DecompositionArg::Regions => Decomposition::Regions,
            }
            .name()
            .to_string()
        }),
        exhaustive: a.exhaustive,
        ramp_angle: a.ramp_angle,
        clearance: a.clearance,
        no_simulate: a.no_simulate,
        post: a.post.clone(),
        ..swarf::Settings::default()
    };
    let post = opts.post()?;
    let opts = opts.seq_options()?;
    let t0 = std::time::Instant::now();
    let sp = swarf::job::toolseq::plan(&job, &db, &opts).map_err(|e| e.in_file(&a.input))?;
    let compute_s = t0.elapsed().as_secs_f64();
    let best = sp.best();
    let input_name = a.input.file_name().and_then(|s| s.to_str()).unwrap_or("input").to_string();
    let tools_file = a.tools.display().to_string();
    let about = swarf::job::toolseq::PostAbout {
        input_name: &input_name,
        tools_file: &tools_file,
        decomposition: opts.decomposition,
        compute_s,
        rest_pictures: !a.no_pictures,
    };
    let posted = swarf::job::toolseq::post_plan(&sp, &db, post, &about)?;
    let mut files: Vec<OutputFile> = Vec::new();
    for p in &posted.programs {
        files.push(OutputFile::new(a.output_dir.join(&p.name), p.gcode.clone()));
        if let Some((name, png)) = &p.rest_picture {
            files.push(OutputFile::new(a.output_dir.join(name), png.clone()));
        }
    }
    let report = posted.report;
    let json = serde_json::to_string_pretty(&report).map_err(|e| Failure { user: false, msg: e.to_string() })?;
    files.push(OutputFile::new(&report_path, json + "\n"));
    if let Some(html) = &a.html {
        let progs: Vec<(&swarf::Toolpath, String, String)> =
            posted.programs.iter().map(|p| (&p.toolpath, p.name.clone(), p.gcode.clone())).collect();
        let title = format!("{input_name} — tool sequence {}", best.tools.join(", "));
        let scene = swarf::view::of_plan(&job, &progs, &opts.sim, title).map_err(|e| e.in_file(&a.input))?;
        files.push(OutputFile::new(html, scene.html()));
    }
    // (all refused before the folder is made: a refused run leaves nothing)
    output::check(&files.iter().map(|f| f.path.as_path()).collect::<Vec<_>>(), &inputs)?;
    std::fs::create_dir_all(&a.output_dir)
        .with_context(|| format!("{}: cannot create the folder", a.output_dir.display()))?;
    output::commit(&files, &inputs)?;
    if !a.quiet {
        println!("{}", plan_table(&sp, a.rows));
        println!(
            "best: {} (D {}), {:.2} min, {:.2} $; {} of {} candidate sequences costed, {} tool runs, {:.2} s",
            best.tools.join(", "),
            best.diameters.iter().map(|d| swarf::post::num(*d, 3)).collect::<Vec<_>>().join(", "),
            best.cost.machining_time_min,
            best.cost.total_cost,
            sp.sequences.len(),
            sp.candidates,
            sp.evaluations,
            compute_s
        );
        if let Some(last) = sp.programs.last().and_then(|p| p.check.as_ref()) {
            let checks: Vec<_> = sp.programs.iter().filter_map(|p| p.check.as_ref()).collect();
            println!(
                "replayed: {} gouges, {} rapid collisions, {} plunges; rest after the last tool {:.0} mm³ ({:.2} % of what it reaches), {:.2} s",
                checks.iter().map(|c| c.gouges).sum::<usize>(),
                checks.iter().map(|c| c.rapid_collisions).sum::<usize>(),
                checks.iter().map(|c| c.plunges).sum::<usize>(),
                last.rest_volume_mm3,
                100.0 * last.rest_fraction,
                sp.simulate_s
            );
        } else {
            println!("not simulated: no gouge, rapid collision or rest figures");
        }
        println!(
            "wrote {} programs into {} and the report {}",
            sp.programs.len(),
            a.output_dir.display(),
            report_path.display()
        );
    }
    Ok(())
}

/// `swarf view`: programs read from G-code, replayed on the job, one page.
fn view(a: ViewArgs) -> Result<(), Failure> {
    let ov = Overrides { tool_diameter: a.tool_diameter, ..placement(&a.place)? };
    let (input, reading) = swarf::io::read_input(&a.case, &ov)?;
    let mut inputs: Vec<&Path> = reading.files.iter().map(PathBuf::as_path).collect();
    inputs.extend(a.programs.iter().map(PathBuf::as_path));
    output::check(&[&a.output], &inputs)?;
    let sim = swarf::SimOptions { res: a.res, ..swarf::SimOptions::DEFAULT };
    sim.validate()?;
    let tool = match &input {
        Input::Flat(j) => j.cutting.tool.clone(),
        Input::Mesh(j) => j.cutting.tool.clone(),
    };
    // --tool N=MM
    let mut sizes: Vec<(u32, f64)> = Vec::new();
    for t in &a.tools {
        let parsed =
            t.split_once('=').and_then(|(n, d)| Some((n.trim().parse::<u32>().ok()?, d.trim().parse::<f64>().ok()?)));
        let Some((n, d)) = parsed else {
            return Err(Failure {
                user: true,
                msg: format!("--tool {t}: expected N=MM, a tool number and its diameter"),
            });
        };
        swarf::Tool { diameter: d, number: n, flutes: 2 }
            .validate()
            .map_err(|e| Failure { user: true, msg: format!("--tool {t}: {e}") })?;
        sizes.push((n, d));
    }
    let mut programs = Vec::new();
    for path in &a.programs {
        let text = std::fs::read(path).map_err(|e| swarf::Error::input(path, "file", e.to_string()))?;
        let text = String::from_utf8(text).map_err(|e| {
            swarf::Error::input(path, format!("byte {}", e.utf8_error().valid_up_to()), "not UTF-8 text")
        })?;
        let opts = swarf::io::gcode::ReadOptions { tool: tool.clone(), clearance_z: None };
        let prog = swarf::io::gcode::read(&text, path, &opts)?;
        if !a.quiet {
            for w in &prog.warnings {
                eprintln!("swarf: warning: {}: {w}", path.display());
            }
        }
        let name = path.file_name().and_then(|s| s.to_str()).unwrap_or("program").to_string();
        let tool_of = |n: Option<u32>| {
            let d = n.and_then(|n| sizes.iter().find(|s| s.0 == n)).map_or(tool.diameter, |s| s.1);
            swarf::Tool { diameter: d, number: n.unwrap_or(tool.number), flutes: tool.flutes }
        };
        if !a.quiet && prog.tools.len() > 1 {
            for t in &prog.tools {
                if t.number.is_none_or(|n| !sizes.iter().any(|s| s.0 == n)) {
                    eprintln!(
                        "swarf: warning: {}: tool {} (line {}) has no --tool N=MM: read as the job's Ø{} mm",
                        path.display(),
                        t.number.map_or("without a number".into(), |n| format!("T{n}")),
                        t.line,
                        tool.diameter
                    );
                }
            }
        }
        let pieces = prog.by_tool(&tool_of);
        programs.push(swarf::view::ReadProgram { name, pieces, units: prog.units, gcode: text });
    }
    let against = match &input {
        Input::Flat(j) => swarf::view::Against::Flat(j),
        Input::Mesh(j) => swarf::view::Against::Mesh(j),
    };
    let scene = swarf::view::of_programs(against, programs, &sim).map_err(|e| e.in_file(&a.case))?;
    output::commit(&[OutputFile::new(&a.output, scene.html())], &inputs)?;
    if !a.quiet {
        for r in &scene.runs {
            for p in &r.programs {
                let f = |k: &str| p.figures.iter().find(|(l, _)| l == k).map_or("-", |(_, v)| v.as_str());
                eprintln!(
                    "{}: {} moves, {}, engagement max / p95 / mean {}, gouges {}, rest {}",
                    p.name,
                    p.toolpath.moves.len(),
                    f("machining time"),
                    f("engagement max / p95 / mean"),
                    f("gouges"),
                    f("rest")
                );
            }
        }
        eprintln!("wrote {}", a.output.display());
    }
    Ok(())
}

/// The cheapest sequences as paper 3's Table 2: diameters, time and cost.
fn shape(a: ShapeArgs) -> Result<(), Failure> {
    use swarf::implicit::{Field, oscillator, shape};
    use swarf::plot::shape as draw;
    output::check(&[&a.output], &[&a.input])?;
    draw::Drawing { title: String::new(), levels: a.levels, resolution: 300, path: None }.validate()?;
    let s = shape::Shape::load(&a.input)?;
    let Some((lo, hi)) = s.bounds() else {
        return Err(swarf::Error::input(&a.input, "shape", "the shape is unbounded: intersect it with a box").into());
    };
    let pad = (hi - lo) * 0.05;
    let (lo, hi) = (lo - pad, hi + pad);
    let mut title = a.input.file_name().and_then(|n| n.to_str()).unwrap_or("shape").to_string();
    let path = match a.spiral {
        None => None,
        Some(w) => {
            let (start, _) = shape::maximum(&s, lo, hi)
                .ok_or_else(|| swarf::Error::input(&a.input, "shape", "the shape is empty (f is nowhere positive)"))?;
            // end a tenth of the stepover inside: the zero set of an R-function shape has corners
            let opts = oscillator::SpiralOptions {
                damping: oscillator::Damping::stepover(w),
                f_end: 0.1 * w,
                ..Default::default()
            };
            // (what stops the spiral is the shape's doing: the message names its file)
            let sp = oscillator::spiral(&s, start, &opts).map_err(|e| e.in_file(&a.input))?;
            title =
                format!("{title}: spiral, {:.1} turns, largest spacing {:.3} (stepover {w})", sp.turns, sp.max_spacing);
            if !a.quiet {
                println!(
                    "{:.1} turns, length {:.1}, largest spacing between turns {:.3}",
                    sp.turns, sp.length, sp.max_spacing
                );
            }
            Some(sp.polyline())
        }
    };
    let d = draw::Drawing { title, levels: a.levels, resolution: 300, path: path.as_deref() };
    let text = draw::svg(&s, lo, hi, &d);
    let bytes = if a.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        swarf::plot::png(&text)?
    } else {
        text.into_bytes()
    };
    output::commit(&[OutputFile::new(&a.output, bytes)], &[&a.input])?;
    if !a.quiet {
        println!("wrote {}", a.output.display());
    }
    Ok(())
}

fn five(a: FiveArgs) -> Result<(), Failure> {
    use swarf::strategy::five::FiveOptions;
    let mut outs: Vec<&Path> = vec![&a.output];
    if let Some(g) = &a.gcode {
        outs.push(g);
    }
    if let Some(p) = &a.picture {
        outs.push(p);
    }
    if let Some(p) = &a.html {
        outs.push(p);
    }
    output::check(&outs, &[&a.input])?;
    let job = swarf::io::five::read_five(&a.input)?;
    let opts = FiveOptions { back: a.back, ..FiveOptions::default() };
    // (the library refuses it too, but of the job; here it is the flag's)
    if let Err(e) = opts.validate() {
        return Err(Failure { user: true, msg: format!("--back: {e}") });
    }
    let p = swarf::job::five::run(&job, &opts).map_err(|e| e.in_file(&a.input))?;
    let mut files = vec![OutputFile::new(&a.output, p.cl.clone().into_bytes())];
    if let Some(g) = &a.gcode {
        files.push(OutputFile::new(g, p.gcode.clone().into_bytes()));
    }
    if let Some(path) = &a.picture {
        let text = p.picture_svg(&job);
        let bytes = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            swarf::plot::png(&text)?
        } else {
            text.into_bytes()
        };
        files.push(OutputFile::new(path, bytes));
    }
    if let Some(path) = &a.html {
        files.push(OutputFile::new(path, swarf::view::of_five(&job, &p).html()));
    }
    output::commit(&files, &[&a.input])?;
    if !a.quiet {
        println!(
            "{}: {} shapes, {} moves, cutting {:.0} mm, rapids {:.0} mm, machining {:.2} min, planned in {:.2} s",
            job.name,
            p.plan.shapes,
            p.plan.moves.len(),
            p.length.0,
            p.length.1,
            p.time_min,
            p.planning_s
        );
        println!("least clearance from a wall {:.3} mm", p.plan.wall_clearance);
        for f in &files {
            println!("wrote {}", f.path.display());
        }
    }
    Ok(())
}

fn plan_table(sp: &swarf::job::toolseq::SeqPlan, rows: usize) -> String {
    let mut out = format!(
        "{:<36} {:>10} {:>12} {:>11} {:>11}\n",
        "tool sequence (diameters)", "time min", "machining $", "tooling $", "total $"
    );
    for s in sp.sequences.iter().take(rows) {
        let d = s.diameters.iter().map(|d| swarf::post::num(*d, 3)).collect::<Vec<_>>().join(", ");
        out.push_str(&format!(
            "{:<36} {:>10.2} {:>12.2} {:>11.2} {:>11.2}\n",
            d, s.cost.machining_time_min, s.cost.machining_cost, s.cost.tooling_cost, s.cost.total_cost
        ));
    }
    if sp.sequences.len() > rows {
        out.push_str(&format!("... {} more in the report\n", sp.sequences.len() - rows));
    }
    out
}
