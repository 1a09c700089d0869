//! A tool sequence as written: one G-code program per tool of the cheapest sequence, each
//! named after its place in the sequence, its tool and its diameter (`01_EM12_D12.ngc`), and
//! the plan's report (JSON), with the simulator's figures of each program where it was
//! replayed. The command line and the Python package write the same files from it.

use super::{Decomposition, SeqPlan};
use crate::error::{Error, Result};
use crate::model::tooldb::ToolDb;
use crate::post::{self, Header, Post};
use crate::toolpath::Toolpath;
use serde_json::{Value, json};

/// One program of the sequence as written.
#[derive(Debug, Clone)]
pub struct PostedProgram {
    /// Its file name (`01_EM12_D12.ngc`).
    pub name: String,
    /// The program, on the post's steps.
    pub toolpath: Toolpath,
    /// Its G-code.
    pub gcode: String,
    /// The stock after it, as a PNG picture (when asked for and the plan was simulated), and
    /// its file name (`01_EM12_D12_rest.png`).
    pub rest_picture: Option<(String, Vec<u8>)>,
}

/// A tool sequence as written: its programs and the report.
#[derive(Debug, Clone)]
pub struct PostedPlan {
    /// The programs, in order.
    pub programs: Vec<PostedProgram>,
    /// The report: the best sequence with each program's figures, the machine, the search's
    /// counts and times, every sequence costed.
    pub report: Value,
}

/// What the report says of the run besides the plan.
#[derive(Debug, Clone, Copy)]
pub struct PostAbout<'a> {
    /// The input's name.
    pub input_name: &'a str,
    /// The tool database's file as given.
    pub tools_file: &'a str,
    /// The decomposition searched with.
    pub decomposition: Decomposition,
    /// Seconds the whole search took.
    pub compute_s: f64,
    /// Draw the stock after each program (`rest_picture`).
    pub rest_pictures: bool,
}

/// A tool's id as a file name: letters, digits and `-` kept, anything else `_`.
pub fn file_safe(id: &str) -> String {
    id.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect()
}

/// Posts the programs of `sp`'s cheapest sequence with `post` and writes the plan's report.
pub fn post_plan(sp: &SeqPlan, db: &ToolDb, post: Post, about: &PostAbout) -> Result<PostedPlan> {
    let best = sp.best();
    let input_name = about.input_name;
    let mut programs = Vec::new();
    let mut entries = Vec::new();
    for (i, p) in sp.programs.iter().enumerate() {
        let stem = format!("{:02}_{}_D{}", i + 1, file_safe(&p.spec.id), post::num(p.spec.diameter, 3));
        let mut tp = p.toolpath.clone();
        tp.quantize(post::COORD_STEP, post::CENTER_STEP);
        let t = tp.totals(db.machine.rapid_feed_mm_min);
        let header = Header {
            lines: vec![
                format!(
                    "{input_name}: z-level roughing, tool {} of {} in sequence {}",
                    i + 1,
                    sp.programs.len(),
                    best.tools.join(" ")
                ),
                format!(
                    "{} {}: D{} mm, {} teeth, width of cut {} mm, depth of cut {} mm",
                    p.spec.id,
                    p.spec.kind,
                    post::num(p.spec.diameter, 3),
                    p.spec.teeth,
                    post::num(p.spec.width_of_cut, 3),
                    post::num(p.spec.depth_of_cut, 3)
                ),
                format!(
                    "feed {} mm/min, spindle {} rpm, cut {:.0} mm, rapid {:.0} mm, {:.2} min at {} mm/min rapid",
                    post::num(p.spec.feed_mm_min(), 1),
                    post::num(p.spec.spindle_rpm(), 0),
                    t.cut_length_mm,
                    t.rapid_length_mm,
                    t.time_min,
                    post::num(db.machine.rapid_feed_mm_min, 0)
                ),
            ],
            spindle_rpm: p.spec.spindle_rpm(),
        };
        let gcode = post::write(&tp, post, &header)?;
        let name = format!("{stem}.ngc");
        let mut entry = json!({
            "file": name,
            "tool": p.spec.id,
            "number": p.number,
            "diameter": p.spec.diameter,
            "feed_mm_min": p.spec.feed_mm_min(),
            "spindle_rpm": p.spec.spindle_rpm(),
            "cut_length_mm": t.cut_length_mm,
            "rapid_length_mm": t.rapid_length_mm,
            "time_min": t.time_min,
        });
        // the simulator's figures, as `rough`'s report names them: gouges, rapid collisions,
        // plunges, the rest after the program (without a replay, the plunges it marks)
        entry["simulated"] = Value::Bool(p.check.is_some());
        match &p.check {
            Some(c) => {
                let v = serde_json::to_value(c)
                    .map_err(|e| Error::Output { what: "plan report".into(), reason: e.to_string() })?;
                if let (Some(obj), Some(v)) = (entry.as_object_mut(), v.as_object()) {
                    obj.extend(v.iter().map(|(k, v)| (k.clone(), v.clone())));
                }
            }
            None => entry["plunges"] = t.plunges.into(),
        }
        let mut rest_picture = None;
        if let (Some(rest), true) = (&sp.rest, about.rest_pictures) {
            let pname = format!("{stem}_rest.png");
            entry["rest_picture"] = Value::String(pname.clone());
            rest_picture = Some((pname, rest.png(i)?));
        }
        entries.push(entry);
        programs.push(PostedProgram { name, toolpath: tp, gcode, rest_picture });
    }
    let report = json!({
        "input": input_name,
        "tools_file": about.tools_file,
        "decomposition": about.decomposition,
        "machine": {
            "cost_per_hour": db.machine.cost_per_hour,
            "rapid_feed_mm_min": db.machine.rapid_feed_mm_min,
            "tool_change_min": db.machine.tool_change_min,
        },
        "best": {
            "tools": best.tools,
            "diameters": best.diameters,
            "machining_time_min": best.cost.machining_time_min,
            "machining_cost": best.cost.machining_cost,
            "tooling_cost": best.cost.tooling_cost,
            "total_cost": best.cost.total_cost,
            "programs": entries,
        },
        "candidates": sp.candidates,
        "costed": sp.sequences.len(),
        "evaluations": sp.evaluations,
        "compute_s": about.compute_s,
        "prepare_s": sp.prepare_s,
        "search_s": sp.search_s,
        "simulate_s": sp.simulate_s,
        "sequences": sp.sequences,
    });
    Ok(PostedPlan { programs, report })
}
