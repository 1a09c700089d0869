//! What the integration tests share: what "clean" and "within the bound" mean for a run,
//! by swarf's own simulator, and an ASCII STL writer for the mesh tests.

// (each test binary uses what it needs)
#![allow(dead_code)]

use swarf::report::Report;

/// Records what keeps a run from being clean: a gouge, a rapid collision or a plunge, or
/// rest of 0.5 % of the reachable area or more (a NaN fails).
pub fn check_clean(what: &str, r: &Report, bad: &mut Vec<String>) {
    if r.gouges != 0 || r.rapid_collisions != 0 || r.plunges != 0 {
        bad.push(format!(
            "{what}: {} gouges, {} rapid collisions, {} plunges",
            r.gouges, r.rapid_collisions, r.plunges
        ));
    }
    if r.rest_fraction.is_nan() || r.rest_fraction >= 0.005 {
        bad.push(format!("{what}: rest {:.4} of the reachable area", r.rest_fraction));
    }
}

/// Records a p99 engagement above `reference + 10°` (a NaN fails).
pub fn check_bound(what: &str, r: &Report, reference: f64, bad: &mut Vec<String>) {
    let bound = reference + 10.0;
    if r.engagement_deg.p99.is_nan() || r.engagement_deg.p99 > bound {
        bad.push(format!("{what}: p99 engagement {:.1}° above {bound}°", r.engagement_deg.p99));
    }
}

/// An ASCII STL of `facets` (each three vertices), the solid named `name`.
pub fn ascii_stl(name: &str, facets: &[[[f64; 3]; 3]]) -> String {
    let mut stl = format!("solid {name}\n");
    for f in facets {
        stl += "facet normal 0 0 0\nouter loop\n";
        for v in f {
            stl += &format!("vertex {} {} {}\n", v[0], v[1], v[2]);
        }
        stl += "endloop\nendfacet\n";
    }
    stl + &format!("endsolid {name}\n")
}
