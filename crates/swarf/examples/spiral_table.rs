//! The table of the docs comparing spirals on the same pocket: the default (ζ per level, the
//! floor chosen by simulation), `--optimise` (the start point chosen too; paper 4 §4) and the
//! best constant ζ, each simulated by swarf and judged by the optimiser's criteria (rest ≤
//! 0.5 %, no gouge, p99 engagement outside the entry ≤ reference + 10°).
//!
//! `cargo run --release -p swarf --example spiral_table -- examples/cases/round_pocket.json ...`

use swarf::job::rough::RoughOptions;
use swarf::strategy::SpiralOptions;
use swarf::strategy::spiral::Trial;
use swarf::strategy::spiral_search::spiral_study;

fn row(name: &str, what: &str, t: &Trial) {
    let sim = t.sim.map_or("not simulated".to_string(), |s| {
        format!(
            "rest {:.2} %, p99 {:.1}°, {}",
            s.rest * 100.0,
            s.p99_deg,
            if s.feasible { "feasible" } else { "infeasible" }
        )
    });
    let choice = match t.choice.zeta {
        Some(z) => format!("ζ {z:.5}"),
        None => format!(
            "ζ per level, floor {:.2}, start {}",
            t.choice.floor,
            t.choice.start.map_or("max of f".to_string(), |p| format!("({:.2}, {:.2})", p.x, p.y))
        ),
    };
    let time = t.time_min.map_or("-".to_string(), |m| format!("{m:.2} min"));
    println!("{name} | {what} | {choice} | {time} | {sim}");
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for path in std::env::args().skip(1) {
        let text = std::fs::read(&path)?;
        let job = swarf::io::case::parse_case(std::path::Path::new(&path), &text)?;
        let opts = RoughOptions::default();
        let name = std::path::Path::new(&path).file_stem().map_or(path.clone(), |s| s.to_string_lossy().into_owned());
        let st = spiral_study(&job, &SpiralOptions::DEFAULT, &opts.link, &opts.sim)?;
        for (what, (choice, trials)) in [("default", &st.default), ("--optimise", &st.optimised)] {
            if let Some(t) = trials.iter().find(|t| t.choice == *choice) {
                row(&name, what, t);
            }
            let sims = trials.iter().filter(|t| t.sim.is_some()).count();
            println!("{name} | {what}: {} candidates, {sims} simulated", trials.len());
        }
        match &st.fixed {
            Some((_, t)) => row(&name, "best fixed ζ", t),
            None => println!("{name} | best fixed ζ | none feasible down to 1e-4"),
        }
    }
    Ok(())
}
