//! The cutting data every job carries (a 2.5D job and a mesh job alike): the tool, the width of
//! cut, the feed, the spindle speed and the rapid rate of the time estimates, with swarf's
//! defaults for what an input does not say ([`Cutting::DEFAULT`]).

use crate::error::{Error, Result, Setting};
use crate::limits;

/// A flat end mill.
#[derive(Debug, Clone, PartialEq)]
pub struct Tool {
    /// Diameter, mm.
    pub diameter: f64,
    /// Tool number written in the program (`T1`).
    pub number: u32,
    /// Number of flutes (for feeds per tooth in reports).
    pub flutes: u32,
}

impl Tool {
    /// The tool of a job that names none: a Ø6 mm two-flute flat end mill, `T1`.
    pub const DEFAULT: Tool = Tool::flat(6.0);

    /// A two-flute flat end mill of the given diameter, tool number 1.
    pub const fn flat(diameter: f64) -> Tool {
        Tool { diameter, number: 1, flutes: 2 }
    }
    /// Radius, mm.
    pub fn radius(&self) -> f64 {
        self.diameter / 2.0
    }
    /// Checks the diameter: a number within [`limits::MIN_TOOL_MM`] and
    /// [`limits::MAX_TOOL_MM`].
    pub fn validate(&self) -> Result<()> {
        let d = self.diameter;
        if !(d.is_finite() && d > 0.0) {
            return Err(Error::setting(
                Setting::ToolDiameter,
                format!("{d} mm: the tool diameter must be a positive number"),
            ));
        }
        if !(limits::MIN_TOOL_MM..=limits::MAX_TOOL_MM).contains(&d) {
            return Err(Error::setting(
                Setting::ToolDiameter,
                format!(
                    "{d} mm: the tool diameter must be between {} and {} mm",
                    limits::MIN_TOOL_MM,
                    limits::MAX_TOOL_MM
                ),
            ));
        }
        Ok(())
    }
}

/// How wide the cut is: a tool engagement angle or a radial stepover.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Width {
    /// Tool engagement angle in degrees, in (0, 180].
    EngagementDeg(f64),
    /// Radial stepover as a fraction of the diameter, in (0, 1].
    Stepover(f64),
}

impl Width {
    /// The width of cut of a job that names none, whatever the input: 25 % of the diameter (60°
    /// in a straight cut), within the 10–25 % a machinist expects of adaptive clearing.
    pub const DEFAULT: Width = Width::Stepover(0.25);

    /// Stepover fraction of a straight cut with this width: `s = (1 - cos θ) / 2`, the inverse of
    /// paper 1 eq. 3, `θ = 90° + asin(2s − 1)`.
    pub fn stepover(self) -> f64 {
        match self {
            Width::Stepover(s) => s,
            Width::EngagementDeg(t) => (1.0 - t.to_radians().cos()) / 2.0,
        }
    }
    /// Engagement angle in degrees of a straight cut with this width (paper 1 eq. 3).
    pub fn engagement_deg(self) -> f64 {
        match self {
            Width::EngagementDeg(t) => t,
            Width::Stepover(s) => 90.0 + (2.0 * s - 1.0).clamp(-1.0, 1.0).asin().to_degrees(),
        }
    }
    /// Checks the range: a stepover in (0, 1], an engagement in (0°, 180°].
    pub fn validate(self) -> Result<()> {
        match self {
            Width::Stepover(s) if !(s > 0.0 && s <= 1.0) => Err(Error::setting(
                Setting::Stepover,
                format!("stepover {s} is outside (0, 1] (a fraction of the tool diameter)"),
            )),
            Width::EngagementDeg(t) if !(t > 0.0 && t <= 180.0) => {
                Err(Error::setting(Setting::Engagement, format!("engagement {t}° is outside (0°, 180°]")))
            }
            _ => Ok(()),
        }
    }
}

/// The tool, the width of cut and the rates a job is cut with.
#[derive(Debug, Clone, PartialEq)]
pub struct Cutting {
    /// The tool.
    pub tool: Tool,
    /// Width of cut.
    pub width: Width,
    /// Cutting feed, mm/min.
    pub feed: f64,
    /// Rapid rate for the time estimates, mm/min.
    pub rapid_rate: f64,
    /// The machine's highest cutting feed, mm/min: the feed raised where the tool cuts little
    /// (chip thinning, paper 1 §5) never goes above it. `None`: the rapid rate.
    pub max_feed: Option<f64>,
    /// Spindle speed, rpm.
    pub spindle_rpm: f64,
}

impl Cutting {
    /// swarf's cutting data for what an input does not say: [`Tool::DEFAULT`] (Ø6 mm),
    /// [`Width::DEFAULT`] (25 %), 1000 mm/min feed, 5000 mm/min rapids for the time estimates,
    /// the machine's highest feed at its rapid rate, 10 000 rpm.
    pub const DEFAULT: Cutting = Cutting {
        tool: Tool::DEFAULT,
        width: Width::DEFAULT,
        feed: 1000.0,
        rapid_rate: 5000.0,
        max_feed: None,
        spindle_rpm: 10000.0,
    };

    /// The default cutting data with a flat end mill of `diameter`.
    pub const fn with_tool_diameter(diameter: f64) -> Cutting {
        Cutting { tool: Tool::flat(diameter), ..Cutting::DEFAULT }
    }

    /// The same cutting data with another width of cut.
    pub const fn with_width(mut self, width: Width) -> Cutting {
        self.width = width;
        self
    }

    /// Checks every value: a positive tool diameter, the width in its range, positive rates.
    pub fn validate(&self) -> Result<()> {
        self.tool.validate()?;
        self.width.validate()?;
        for (setting, v, what) in [
            (Setting::Feed, self.feed, "mm/min: the feed must be positive"),
            (Setting::RapidRate, self.rapid_rate, "mm/min: the rapid rate must be positive"),
            (Setting::SpindleSpeed, self.spindle_rpm, "rpm: the spindle speed must be positive"),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::setting(setting, format!("{v} {what}")));
            }
            if v > limits::MAX_RATE {
                return Err(Error::setting(setting, format!("{v}: at most {}", limits::MAX_RATE)));
            }
        }
        if let Some(m) = self.max_feed
            && !(m.is_finite() && m >= self.feed && m <= limits::MAX_RATE)
        {
            return Err(Error::setting(
                Setting::MaxFeed,
                format!(
                    "{m} mm/min: the highest feed must be a number no lower than the feed ({} mm/min) and at most {}",
                    self.feed,
                    limits::MAX_RATE
                ),
            ));
        }
        Ok(())
    }

    /// Radial stepover in mm: the width's stepover fraction of the tool's diameter.
    pub fn stepover_mm(&self) -> f64 {
        self.width.stepover() * self.tool.diameter
    }

    /// The machine's highest cutting feed, mm/min ([`Cutting::max_feed`], the rapid rate when
    /// it is not given).
    pub fn max_feed(&self) -> f64 {
        self.max_feed.unwrap_or(self.rapid_rate)
    }

    /// How far a feed boost of `boost` may raise the feed of this cutting data: `boost`, down
    /// to what keeps the feed within the machine's highest, and at least 1.
    pub fn boost_within(&self, boost: f64) -> f64 {
        boost.min(self.max_feed() / self.feed).max(1.0)
    }
}

impl Default for Cutting {
    fn default() -> Self {
        Cutting::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_bad_value_names_its_setting() {
        let bad = |c: Cutting| match c.validate() {
            Err(Error::Setting { setting, .. }) => setting,
            other => panic!("{other:?}"),
        };
        assert!(Cutting::DEFAULT.validate().is_ok());
        assert_eq!(bad(Cutting::with_tool_diameter(-1.0)), Setting::ToolDiameter);
        assert_eq!(bad(Cutting { width: Width::Stepover(1.5), ..Cutting::DEFAULT }), Setting::Stepover);
        assert_eq!(bad(Cutting { width: Width::EngagementDeg(0.0), ..Cutting::DEFAULT }), Setting::Engagement);
        assert_eq!(bad(Cutting { feed: f64::NAN, ..Cutting::DEFAULT }), Setting::Feed);
        assert_eq!(bad(Cutting { rapid_rate: 0.0, ..Cutting::DEFAULT }), Setting::RapidRate);
        assert_eq!(bad(Cutting { spindle_rpm: -5.0, ..Cutting::DEFAULT }), Setting::SpindleSpeed);
        assert_eq!(bad(Cutting { max_feed: Some(500.0), ..Cutting::DEFAULT }), Setting::MaxFeed);
        assert_eq!(bad(Cutting { max_feed: Some(f64::INFINITY), ..Cutting::DEFAULT }), Setting::MaxFeed);
        // the boost stays under the machine's highest feed, the rapid rate by default
        assert_eq!(Cutting::DEFAULT.boost_within(3.0), 3.0);
        assert_eq!(Cutting { max_feed: Some(1500.0), ..Cutting::DEFAULT }.boost_within(3.0), 1.5);
        assert_eq!(
            Cutting { rapid_rate: 800.0, max_feed: None, feed: 1000.0, ..Cutting::DEFAULT }.boost_within(3.0),
            1.0
        );
    }

    #[test]
    fn width_conversions_are_inverse() {
        for s in [0.1, 0.25, 0.4, 0.5, 0.9] {
            let t = Width::Stepover(s).engagement_deg();
            assert!((Width::EngagementDeg(t).stepover() - s).abs() < 1e-12);
        }
        assert!((Width::Stepover(0.5).engagement_deg() - 90.0).abs() < 1e-12);
    }
}
