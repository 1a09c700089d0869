//! A tool database and paper 3's cost model (El-Midany et al., §2 eqs. 1–4, §6 Table 1).
//!
//! The database is a JSON file of the machine (cost per hour, rapid feed, tool change time) and
//! the tools (teeth, diameter, width and depth of cut, feed per tooth, cutting speed, price,
//! life), in the form of the benchmark suite's `tools_elmidany.json`; feeds come from the
//! cutting data (`n = 1000·vc / (π·D)`, `F = fz·z·n`), and the cost of a sequence of tools is
//! the machine's time (cutting, rapids and tool changes) at its hourly cost plus, for each
//! tool, its cutting time's share of its price over its life (eqs. 2–4). The fields and the
//! formulas are in `docs/zlevel.md`.

use crate::error::{Error, Result};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The machine's data.
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    /// Machine cost, $/h (`C_mc`).
    pub cost_per_hour: f64,
    /// Rapid feed, mm/min (`f_air`).
    pub rapid_feed_mm_min: f64,
    /// Tool change time, min (`t_ch`).
    pub tool_change_min: f64,
}

/// One tool of the database.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolSpec {
    /// Name (`T1`).
    pub id: String,
    /// Kind, free text (`indexable insert`, `solid carbide`).
    pub kind: String,
    /// Number of teeth.
    pub teeth: u32,
    /// Diameter, mm.
    pub diameter: f64,
    /// Radial width of cut, mm.
    pub width_of_cut: f64,
    /// Axial depth of cut (the step-down), mm.
    pub depth_of_cut: f64,
    /// Feed per tooth, mm.
    pub feed_per_tooth: f64,
    /// Cutting speed, m/min.
    pub cutting_speed_m_min: f64,
    /// Price, $ (`C_t`).
    pub price: f64,
    /// Tool life, min (`t_lf`).
    pub life_min: f64,
}

impl ToolSpec {
    /// Spindle speed from the cutting speed, rpm: `n = 1000·vc / (π·D)`.
    pub fn spindle_rpm(&self) -> f64 {
        1000.0 * self.cutting_speed_m_min / (std::f64::consts::PI * self.diameter)
    }
    /// Feed from the feed per tooth, mm/min: `F = fz·z·n`.
    pub fn feed_mm_min(&self) -> f64 {
        self.feed_per_tooth * f64::from(self.teeth) * self.spindle_rpm()
    }
    /// Width of cut as a fraction of the diameter.
    pub fn stepover(&self) -> f64 {
        self.width_of_cut / self.diameter
    }
}

/// A machine and its tools.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolDb {
    /// The machine.
    pub machine: Machine,
    /// The tools, in the file's order.
    pub tools: Vec<ToolSpec>,
}

/// What one tool of a sequence does: its path lengths and feed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolRun {
    /// Cutting path length, mm (`l_mc`).
    pub cut_mm: f64,
    /// Rapid path length, mm (`l_air`).
    pub air_mm: f64,
    /// Cutting feed, mm/min (`f_mc`).
    pub feed_mm_min: f64,
    /// Tool price, $.
    pub price: f64,
    /// Tool life, min.
    pub life_min: f64,
}

/// Time and cost of a sequence of tools (eqs. 2–4).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Cost {
    /// Machining time, min: cutting and rapids of every tool plus the tool changes.
    pub machining_time_min: f64,
    /// Machining cost `Mc`, $.
    pub machining_cost: f64,
    /// Tooling cost `Tc`, $.
    pub tooling_cost: f64,
    /// `C = Mc + Tc`, $.
    pub total_cost: f64,
}

impl Machine {
    /// The cost of running `runs` in sequence (eqs. 2–4).
    pub fn cost(&self, runs: &[ToolRun]) -> Cost {
        let mut t = 0.0;
        let mut tc = 0.0;
        for r in runs {
            let cut_min = r.cut_mm / r.feed_mm_min;
            t += cut_min + r.air_mm / self.rapid_feed_mm_min;
            tc += cut_min * r.price / r.life_min;
        }
        let t = t + runs.len() as f64 * self.tool_change_min;
        let mc = self.cost_per_hour / 60.0 * t;
        Cost { machining_time_min: t, machining_cost: mc, tooling_cost: tc, total_cost: mc + tc }
    }
}

struct Ctx {
    file: PathBuf,
}

impl Ctx {
    fn err(&self, place: impl Into<String>, reason: impl Into<String>) -> Error {
        Error::input(&self.file, place, reason)
    }
    fn pos(&self, obj: &Value, key: &str, place: &str) -> Result<f64> {
        let v = obj.get(key).ok_or_else(|| self.err(format!("{place}.{key}"), "missing"))?;
        match v.as_f64() {
            Some(x) if x.is_finite() && x > 0.0 && x <= crate::limits::MAX_NUMBER => Ok(x),
            Some(x) if x.is_finite() && x > 0.0 => Err(self.err(
                format!("{place}.{key}"),
                format!("{x}: outside ±{:e}, the largest number swarf reads", crate::limits::MAX_NUMBER),
            )),
            _ => Err(self.err(format!("{place}.{key}"), format!("expected a positive number, found {v}"))),
        }
    }
}

impl ToolDb {
    /// Reads a database file.
    pub fn read(path: &Path) -> Result<ToolDb> {
        let bytes = std::fs::read(path).map_err(|e| Error::input(path, "file", format!("cannot read: {e}")))?;
        Self::parse(path, &bytes)
    }

    /// Parses database JSON; `path` names the file in messages.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<ToolDb> {
        let cx = Ctx { file: path.to_path_buf() };
        let root: Value = serde_json::from_slice(bytes)
            .map_err(|e| cx.err(format!("line {} column {}", e.line(), e.column()), format!("not valid JSON: {e}")))?;
        let m = root.get("machine").ok_or_else(|| {
            cx.err(
                "machine",
                "missing: {\"cost_per_hour\": $, \"rapid_feed_mm_min\": mm/min, \"tool_change_min\": min}",
            )
        })?;
        let tool_change_min = match m.get("tool_change_min") {
            None => 0.0,
            Some(v) => v.as_f64().filter(|x| x.is_finite() && *x >= 0.0).ok_or_else(|| {
                cx.err("machine.tool_change_min", format!("expected zero or a positive number, found {v}"))
            })?,
        };
        let machine = Machine {
            cost_per_hour: cx.pos(m, "cost_per_hour", "machine")?,
            rapid_feed_mm_min: cx.pos(m, "rapid_feed_mm_min", "machine")?,
            tool_change_min,
        };
        if machine.rapid_feed_mm_min > crate::limits::MAX_RATE {
            return Err(cx.err(
                "machine.rapid_feed_mm_min",
                format!("{} mm/min: at most {}", machine.rapid_feed_mm_min, crate::limits::MAX_RATE),
            ));
        }
        let list =
            root.get("tools").and_then(Value::as_array).ok_or_else(|| cx.err("tools", "missing: a list of tools"))?;
        if list.is_empty() {
            return Err(cx.err("tools", "the list is empty"));
        }
        let mut tools = Vec::with_capacity(list.len());
        for (i, t) in list.iter().enumerate() {
            let place = format!("tools[{i}]");
            if !t.is_object() {
                return Err(cx.err(&place, format!("expected a tool {{\"id\": …, \"diameter\": …}}, found {t}")));
            }
            let id = t.get("id").and_then(Value::as_str).map_or_else(|| format!("T{}", i + 1), str::to_string);
            let teeth = t
                .get("teeth")
                .and_then(Value::as_u64)
                .filter(|n| *n >= 1 && *n <= 1000)
                .ok_or_else(|| cx.err(format!("{place}.teeth"), "expected a whole number of teeth, at least 1"))?;
            let spec = ToolSpec {
                kind: t.get("type").and_then(Value::as_str).unwrap_or("").to_string(),
                teeth: teeth as u32,
                diameter: cx.pos(t, "diameter", &place)?,
                width_of_cut: cx.pos(t, "width_of_cut", &place)?,
                depth_of_cut: cx.pos(t, "depth_of_cut", &place)?,
                feed_per_tooth: cx.pos(t, "feed_per_tooth", &place)?,
                cutting_speed_m_min: cx.pos(t, "cutting_speed_m_min", &place)?,
                price: cx.pos(t, "price", &place)?,
                life_min: cx.pos(t, "life_min", &place)?,
                id,
            };
            if let Err(Error::Setting { reason, .. }) = crate::model::Tool::flat(spec.diameter).validate() {
                return Err(cx.err(format!("{place}.diameter"), reason));
            }
            for (key, v, unit) in [
                ("cutting_speed_m_min", spec.spindle_rpm(), "rpm of spindle speed"),
                ("feed_per_tooth", spec.feed_mm_min(), "mm/min of feed"),
            ] {
                if v > crate::limits::MAX_RATE {
                    return Err(cx.err(
                        format!("{place}.{key}"),
                        format!("it makes {v:.0} {unit}: at most {}", crate::limits::MAX_RATE),
                    ));
                }
            }
            if spec.depth_of_cut > crate::limits::MAX_COORD_MM {
                return Err(cx.err(
                    format!("{place}.depth_of_cut"),
                    format!("{} mm: at most {} mm", spec.depth_of_cut, crate::limits::MAX_COORD_MM),
                ));
            }
            if spec.width_of_cut > spec.diameter {
                return Err(cx.err(
                    format!("{place}.width_of_cut"),
                    format!("{} mm is wider than the tool ({} mm)", spec.width_of_cut, spec.diameter),
                ));
            }
            if tools.iter().any(|o: &ToolSpec| o.id == spec.id) {
                return Err(cx.err(format!("{place}.id"), format!("{:?} is used twice", spec.id)));
            }
            tools.push(spec);
        }
        Ok(ToolDb { machine, tools })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE1: &str = r#"{
     "machine": {"cost_per_hour": 50.0, "rapid_feed_mm_min": 30000.0, "tool_change_min": 0.5},
     "tools": [
      {"id": "T1", "type": "indexable insert", "teeth": 7, "diameter": 80, "width_of_cut": 40, "depth_of_cut": 4, "feed_per_tooth": 0.2, "cutting_speed_m_min": 80, "price": 168, "life_min": 60},
      {"id": "T8", "type": "solid carbide", "teeth": 4, "diameter": 10, "width_of_cut": 5, "depth_of_cut": 1, "feed_per_tooth": 0.03, "cutting_speed_m_min": 60, "price": 120, "life_min": 45}
     ]}"#;

    #[test]
    fn feeds_from_cutting_data() {
        let db = ToolDb::parse(Path::new("tools.json"), TABLE1.as_bytes()).unwrap();
        let t1 = &db.tools[0];
        // n = 1000·80 / (π·80) = 318.31 rpm, F = 0.2·7·n = 445.6 mm/min
        assert!((t1.spindle_rpm() - 318.3099).abs() < 1e-3);
        assert!((t1.feed_mm_min() - 445.6338).abs() < 1e-3);
        assert_eq!(t1.stepover(), 0.5);
        // T8: n = 1909.86 rpm, F = 0.03·4·n = 229.18 mm/min
        assert!((db.tools[1].feed_mm_min() - 229.1831).abs() < 1e-3);
    }

    #[test]
    fn cost_of_a_sequence() {
        let m = Machine { cost_per_hour: 60.0, rapid_feed_mm_min: 10_000.0, tool_change_min: 0.5 };
        let runs = [
            ToolRun { cut_mm: 1000.0, air_mm: 10_000.0, feed_mm_min: 500.0, price: 100.0, life_min: 50.0 },
            ToolRun { cut_mm: 300.0, air_mm: 0.0, feed_mm_min: 100.0, price: 40.0, life_min: 20.0 },
        ];
        let c = m.cost(&runs);
        // time: 2 + 1 + 3 + 0 + 2·0.5 = 7 min; Mc = 60/60·7 = 7 $; Tc = 2·100/50 + 3·40/20 = 10 $
        assert!((c.machining_time_min - 7.0).abs() < 1e-12);
        assert!((c.machining_cost - 7.0).abs() < 1e-12);
        assert!((c.tooling_cost - 10.0).abs() < 1e-12);
        assert!((c.total_cost - 17.0).abs() < 1e-12);
    }

    #[test]
    fn names_the_bad_field() {
        let bad = TABLE1.replacen("\"teeth\": 4", "\"teeth\": 0", 1);
        let e = ToolDb::parse(Path::new("tools.json"), bad.as_bytes()).unwrap_err().to_string();
        assert!(e.starts_with("tools.json: tools[1].teeth:"), "{e}");
        let bad = TABLE1.replacen("\"diameter\": 80", "\"diameter\": -80", 1);
        let e = ToolDb::parse(Path::new("tools.json"), bad.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("tools[0].diameter: expected a positive number"), "{e}");
        let bad = TABLE1.replacen("\"T8\"", "\"T1\"", 1);
        let e = ToolDb::parse(Path::new("tools.json"), bad.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("tools[1].id: \"T1\" is used twice"), "{e}");
        let e = ToolDb::parse(Path::new("tools.json"), b"{\"machine\": 3,").unwrap_err().to_string();
        assert!(e.contains("line 1"), "{e}");
    }
}
