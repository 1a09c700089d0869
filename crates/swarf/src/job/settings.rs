//! A run's options by name, as a user gives them: the command line's flags and the Python
//! package's keywords both fill a [`Settings`], and [`Settings::rough_options`] and
//! [`Settings::seq_options`] turn it into the library's options structs, on top of their
//! defaults and checked once, here. What a setting leaves out (`None`, `false`) keeps the
//! library's default, so that the same settings give the same program whichever face set them.

use crate::error::{Error, Result, Setting};
use crate::geom::DVec2;
use crate::job::rough::RoughOptions;
use crate::job::toolseq::{Decomposition, SeqOptions};
use crate::plan::LinkOptions;
use crate::post::Post;
use crate::sim::{SimEngine, SimOptions};
use crate::strategy::{
    AdaptiveOptions, MedialOptions, OffsetOptions, OffsetOrder, SpiralOptions, Strategy, ZigzagOptions,
};

/// The options of a run by name; every field left `None` (or `false`) keeps the library's
/// default. Each field is named as the command line's flag (`--tool-diameter` is
/// `tool_diameter`, and so on).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Settings {
    /// The clearing strategy: one of [`Strategy::NAMES`].
    pub strategy: Option<String>,
    /// The controller dialect: one of [`Post::NAMES`].
    pub post: Option<String>,
    /// Conventional instead of climb milling.
    pub conventional: bool,
    /// Order of offset passes: `inside-out` or `outside-in`.
    pub order: Option<String>,
    /// Zigzag row angle, degrees.
    pub angle: Option<f64>,
    /// Radial stock the roughing leaves for the finishing contour, mm.
    pub stock_to_leave: Option<f64>,
    /// A finishing contour at every level.
    pub finish: bool,
    /// Ramp and helix angle, degrees (a tool sequence's largest ramp angle).
    pub ramp_angle: Option<f64>,
    /// Adaptive: engagement above the reference wall-following may reach, degrees.
    pub overshoot: Option<f64>,
    /// How far the feed may rise where the tool cuts little (1 = off).
    pub feed_boost: Option<f64>,
    /// Links through cleared space as feed moves instead of rapids at depth.
    pub feed_links: bool,
    /// Z-level jobs: level by level instead of region by region through the levels.
    pub level_by_level: bool,
    /// Medial: follow every circle all the way round.
    pub full_circles: bool,
    /// Spiral: a constant damping ζ.
    pub zeta: Option<f64>,
    /// Spiral: the start point, mm.
    pub spiral_start: Option<DVec2>,
    /// Spiral: the least gap between turns, a fraction of the stepover.
    pub spiral_floor: Option<f64>,
    /// Spiral: choose the start point too.
    pub optimise: bool,
    /// Arc-fitting tolerance, mm.
    pub arc_tolerance: Option<f64>,
    /// Clearance above the top of the job for travel, mm.
    pub clearance: Option<f64>,
    /// Simulation cell size (or sample spacing), mm.
    pub res: Option<f64>,
    /// The simulator that proves the program: `raster` or `sdf`.
    pub sim: Option<String>,
    /// Skip the simulation.
    pub no_simulate: bool,
    /// The exact engagement at every sample of the simulation.
    pub exact_every_sample: bool,
    /// Tool sequences: `trim` (Algorithm 4) or `regions` (Algorithm 3).
    pub decomposition: Option<String>,
    /// Tool sequences: cost every candidate sequence instead of pruning by the lower bound.
    pub exhaustive: bool,
}

/// An offset order by its name ([`OffsetOrder::name`]).
pub fn order_of(name: &str) -> Option<OffsetOrder> {
    OffsetOrder::ALL.into_iter().find(|o| o.name() == name)
}

/// A decomposition by its name ([`Decomposition::name`]).
pub fn decomposition_of(name: &str) -> Option<Decomposition> {
    Decomposition::ALL.into_iter().find(|d| d.name() == name)
}

impl Settings {
    /// The strategy the settings name, with the options of it they set. The options of every
    /// strategy are checked, whichever strategy runs: a bad value is an error even where it
    /// would not be used.
    pub fn strategy(&self) -> Result<Strategy> {
        let adaptive = AdaptiveOptions {
            overshoot_deg: self.overshoot.unwrap_or(AdaptiveOptions::DEFAULT.overshoot_deg),
            ..AdaptiveOptions::DEFAULT
        };
        let order = match self.order.as_deref() {
            None => OffsetOptions::DEFAULT.order,
            Some(n) => order_of(n).ok_or_else(|| {
                Error::setting(Setting::OffsetOrder, format!("{n:?}: expected inside-out or outside-in"))
            })?,
        };
        let all = [
            Strategy::Adaptive(adaptive.clone()),
            Strategy::Offset(OffsetOptions { order }),
            Strategy::Zigzag(ZigzagOptions { angle_deg: self.angle.unwrap_or(ZigzagOptions::DEFAULT.angle_deg) }),
            Strategy::Medial(MedialOptions { cut_back: !self.full_circles }),
            Strategy::Spiral(SpiralOptions {
                zeta: self.zeta,
                start: self.spiral_start,
                floor: self.spiral_floor,
                optimise: self.optimise,
                search_cells: SpiralOptions::DEFAULT.search_cells,
                adaptive,
            }),
        ];
        for s in &all {
            s.validate()?;
        }
        let name = self.strategy.as_deref().unwrap_or(Strategy::DEFAULT.name());
        all.into_iter().find(|s| s.name() == name).ok_or_else(|| {
            Error::setting(Setting::Strategy, format!("{name:?}: expected one of {}", Strategy::NAMES.join(", ")))
        })
    }

    /// The controller dialect the settings name (the library's default when none).
    pub fn post(&self) -> Result<Post> {
        match self.post.as_deref() {
            None => Ok(Post::DEFAULT),
            Some(n) => Post::parse(n).ok_or_else(|| {
                Error::setting(Setting::Post, format!("{n:?}: expected one of {}", Post::NAMES.join(", ")))
            }),
        }
    }

    /// The simulation settings.
    pub fn sim(&self) -> Result<SimOptions> {
        let engine = match self.sim.as_deref() {
            None => SimOptions::DEFAULT.engine,
            Some(n) => n.parse::<SimEngine>()?,
        };
        let sim =
            SimOptions { res: self.res, engine, exact_every_sample: self.exact_every_sample, ..SimOptions::DEFAULT };
        sim.validate()?;
        Ok(sim)
    }

    /// The options of `rough` (2.5D and z-level), checked; `input_name` names the input in the
    /// program's header and the report.
    ///
    /// ```
    /// use swarf::{Error, Setting, Settings, Strategy};
    /// let s = Settings { strategy: Some("offset".into()), ramp_angle: Some(4.0), ..Settings::default() };
    /// let opts = s.rough_options("pocket.json")?;
    /// assert_eq!(opts.strategy.name(), "offset");
    /// assert_eq!(opts.link.ramp_angle_deg, 4.0);
    /// // a bad value names its setting
    /// let bad = Settings { ramp_angle: Some(95.0), ..Settings::default() }.rough_options("");
    /// assert!(matches!(bad, Err(Error::Setting { setting: Setting::RampAngle, .. })));
    /// # Ok::<(), swarf::Error>(())
    /// ```
    pub fn rough_options(&self, input_name: impl Into<String>) -> Result<RoughOptions> {
        let d = LinkOptions::DEFAULT;
        let link = LinkOptions {
            climb: !self.conventional,
            stock_to_leave: self.stock_to_leave.unwrap_or(d.stock_to_leave),
            finish: self.finish,
            ramp_angle_deg: self.ramp_angle.unwrap_or(d.ramp_angle_deg),
            arc_tol: self.arc_tolerance.unwrap_or(d.arc_tol),
            clearance: self.clearance.unwrap_or(d.clearance),
            feed_boost: self.feed_boost.unwrap_or(d.feed_boost),
            feed_links: self.feed_links,
            by_level: self.level_by_level,
            ..d
        };
        let opts = RoughOptions {
            strategy: self.strategy()?,
            link,
            post: self.post()?,
            sim: self.sim()?,
            simulate: !self.no_simulate,
            input_name: input_name.into(),
        };
        opts.validate()?;
        Ok(opts)
    }

    /// The options of a tool-sequence search ([`crate::plan_tools`]), checked: its
    /// decomposition, pruning, ramp angle, clearance and simulation.
    pub fn seq_options(&self) -> Result<SeqOptions> {
        let d = SeqOptions::DEFAULT;
        let decomposition = match self.decomposition.as_deref() {
            None => d.decomposition,
            Some(n) => decomposition_of(n)
                .ok_or_else(|| Error::setting(Setting::Decomposition, format!("{n:?}: expected trim or regions")))?,
        };
        let opts = SeqOptions {
            decomposition,
            prune: !self.exhaustive,
            ramp_deg: self.ramp_angle.unwrap_or(d.ramp_deg),
            clearance: self.clearance.unwrap_or(d.clearance),
            simulate: !self.no_simulate,
            ..d
        };
        opts.validate()?;
        Ok(opts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_set_is_the_library_defaults() {
        let o = Settings::default().rough_options("").unwrap();
        assert_eq!(o, RoughOptions::DEFAULT);
        assert_eq!(Settings::default().seq_options().unwrap(), SeqOptions::DEFAULT);
    }

    #[test]
    fn names_are_checked_and_name_their_setting() {
        let bad = |s: Settings| match s.rough_options("") {
            Err(Error::Setting { setting, reason }) => (setting, reason),
            other => panic!("{other:?}"),
        };
        let (s, r) = bad(Settings { strategy: Some("trochoidal".into()), ..Settings::default() });
        assert_eq!(s, Setting::Strategy);
        assert!(r.contains("adaptive"), "{r}");
        assert_eq!(bad(Settings { post: Some("fanuc".into()), ..Settings::default() }).0, Setting::Post);
        assert_eq!(bad(Settings { order: Some("random".into()), ..Settings::default() }).0, Setting::OffsetOrder);
        assert_eq!(bad(Settings { sim: Some("voxel".into()), ..Settings::default() }).0, Setting::SimEngine);
        // a bad value of a strategy that does not run is still an error
        assert_eq!(bad(Settings { angle: Some(f64::NAN), ..Settings::default() }).0, Setting::ZigzagAngle);
        let seq = Settings { decomposition: Some("slices".into()), ..Settings::default() }.seq_options();
        assert!(matches!(seq, Err(Error::Setting { setting: Setting::Decomposition, .. })), "{seq:?}");
    }

    #[test]
    fn what_is_set_reaches_the_options() {
        let s = Settings {
            strategy: Some("zigzag".into()),
            angle: Some(30.0),
            conventional: true,
            post: Some("grbl".into()),
            res: Some(0.05),
            no_simulate: true,
            ramp_angle: Some(5.0),
            ..Settings::default()
        };
        let o = s.rough_options("x.json").unwrap();
        assert_eq!(o.strategy, Strategy::Zigzag(ZigzagOptions { angle_deg: 30.0 }));
        assert!(!o.link.climb && !o.simulate);
        assert_eq!((o.post, o.sim.res, o.link.ramp_angle_deg), (Post::Grbl, Some(0.05), 5.0));
        assert_eq!(o.input_name, "x.json");
        assert_eq!(s.seq_options().unwrap().ramp_deg, 5.0);
    }
}
