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

/// xorshift64* seeded by splitmix64.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Rng(z.max(1))
    }
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unit()
    }
    /// Uniform integer in [a, b].
    pub fn int(&mut self, a: usize, b: usize) -> usize {
        a + (self.next_u64() % (b - a + 1) as u64) as usize
    }
    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
}
