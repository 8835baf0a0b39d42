//! A population of bodies the fixtures lack (issue #13, item 4): hm08 macro
//! parameters sampled with a fixed seed across sex, age, weight, muscle,
//! height, proportions and ethnic mix, extremes included, and a *scan-like*
//! copy of any body: re-meshed to an unrelated topology with normal noise.
//!
//! **Sampling.** The first [`CORNERS`] bodies are the corners that break
//! things first — the lightest and heaviest, shortest and tallest, least and
//! most muscled women and men, at 25 and 90 years, with ideal and
//! uncommon proportions — each with a pure ethnic mix in turn. The rest
//! are drawn uniformly from the range of every macro the embedded model
//! takes (age 25–90 years: [`ADULT_AGE`]..1; the others on [0, 1]) with ethnic weights
//! uniform on the simplex. SplitMix64 (Steele, Lea & Flood 2014) drives it:
//! the same seed gives the same bodies on every machine.
//!
//! **Scan-like copies** ([`scan_like`]): [`remesh_unrelated`] to a target face
//! count (no vertex of the result is a vertex of the input), then every
//! vertex moved along its normal by a uniform amount in `[−noise, +noise]`.
//!
//! Failure modes: only those of the re-meshing ([`SimplifyError`]).

use glam::DVec3;

use super::model::{MacroParams, MannequinParams};
use crate::geom::mesh::TriMesh;
use crate::geom::simplify::{remesh_unrelated, SimplifyError, SimplifyOptions};

/// The youngest age the embedded model takes: MakeHuman's age macro 0.5,
/// 25 years (its targets below that are not embedded; 1.0 is 90 years).
pub const ADULT_AGE: f64 = 0.5;

/// How many of the first bodies are the planted extremes.
pub const CORNERS: usize = 10;

/// One sampled body.
#[derive(Debug, Clone, PartialEq)]
pub struct PopulationBody {
    /// A name that says what it is, e.g. `pop07-m-heavy-short`.
    pub name: String,
    /// Its model parameters.
    pub params: MannequinParams,
}

/// SplitMix64: small, fast and the same everywhere.
#[derive(Debug, Clone)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn word(x: f64, low: &'static str, mid: &'static str, high: &'static str) -> &'static str {
    if x < 0.34 {
        low
    } else if x > 0.66 {
        high
    } else {
        mid
    }
}

fn named(i: usize, m: MacroParams) -> PopulationBody {
    let name = format!(
        "pop{i:02}-{}-{}-{}",
        if m.gender < 0.5 { "f" } else { "m" },
        word(m.weight, "slim", "average", "heavy"),
        word(m.height, "short", "medium", "tall"),
    );
    PopulationBody { name, params: MannequinParams { macros: m, modifiers: Default::default() } }
}

/// `count` bodies sampled with `seed` (module docs): the [`CORNERS`] planted
/// extremes first, then uniform draws.
pub fn sample_population(count: usize, seed: u64) -> Vec<PopulationBody> {
    let race = |k: usize| -> [f64; 3] {
        let mut r = [0.0; 3];
        r[k % 3] = 1.0;
        r
    };
    // (gender, age, muscle, weight, height, proportions)
    let corners: [(f64, f64, f64, f64, f64, f64); CORNERS] = [
        (0.0, 0.5, 0.5, 0.0, 0.0, 0.5),
        (0.0, 0.5, 0.5, 1.0, 1.0, 0.5),
        (1.0, 0.5, 0.5, 0.0, 1.0, 0.5),
        (1.0, 0.5, 0.5, 1.0, 0.0, 0.5),
        (0.0, 1.0, 0.0, 1.0, 0.5, 0.0),
        (1.0, 1.0, 0.0, 0.8, 0.5, 0.0),
        (0.0, ADULT_AGE, 1.0, 0.3, 0.7, 1.0),
        (1.0, ADULT_AGE, 1.0, 0.5, 0.7, 1.0),
        (0.5, 0.6, 0.5, 0.5, 0.5, 0.5),
        (1.0, 0.5, 0.0, 0.0, 0.0, 0.0),
    ];
    let mut rng = SplitMix64(seed);
    (0..count)
        .map(|i| {
            let m = if let Some(&(gender, age, muscle, weight, height, proportions)) = corners.get(i) {
                let [african, asian, caucasian] = race(i);
                MacroParams { gender, age, muscle, weight, height, proportions, african, asian, caucasian }
            } else {
                let gender = if rng.unit() < 0.5 { 0.0 } else { 1.0 };
                let age = ADULT_AGE + (1.0 - ADULT_AGE) * rng.unit();
                let (muscle, weight, height, proportions) = (rng.unit(), rng.unit(), rng.unit(), rng.unit());
                // uniform on the simplex: sorted uniforms' gaps
                let (a, b) = (rng.unit(), rng.unit());
                let (lo, hi) = (a.min(b), a.max(b));
                MacroParams {
                    gender,
                    age,
                    muscle,
                    weight,
                    height,
                    proportions,
                    african: lo,
                    asian: hi - lo,
                    caucasian: 1.0 - hi,
                }
            };
            named(i, m)
        })
        .collect()
}

/// A scan-like copy of `mesh` (module docs): re-meshed to about
/// `target_faces` triangles of an unrelated topology, then each vertex moved
/// along its normal by a uniform amount in `[−noise_m, noise_m]` (metres)
/// drawn with `seed`.
///
/// # Errors
/// [`SimplifyError`] from the re-meshing.
pub fn scan_like(mesh: &TriMesh, target_faces: usize, noise_m: f64, seed: u64) -> Result<TriMesh, SimplifyError> {
    let remeshed = remesh_unrelated(mesh, target_faces, &SimplifyOptions::default())?;
    let normals = remeshed.vertex_normals();
    let mut rng = SplitMix64(seed);
    let positions: Vec<DVec3> =
        remeshed.positions().iter().zip(&normals).map(|(p, n)| *p + *n * noise_m * (2.0 * rng.unit() - 1.0)).collect();
    // the same triangles over moved positions; should the noise ever make a triangle
    // degenerate (not for noise well below the edge length), the noiseless re-mesh
    Ok(TriMesh::new(positions, remeshed.triangles().to_vec()).unwrap_or(remeshed))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_seed_gives_the_same_population_and_extremes_come_first() {
        let a = sample_population(40, 7);
        assert_eq!(a, sample_population(40, 7));
        assert_ne!(a[CORNERS..], sample_population(40, 8)[CORNERS..]);
        assert_eq!(a.len(), 40);
        for b in &a {
            let m = &b.params.macros;
            for x in [m.gender, m.muscle, m.weight, m.height, m.proportions, m.african, m.asian, m.caucasian] {
                assert!((0.0..=1.0).contains(&x), "{}: {m:?}", b.name);
            }
            assert!(m.age >= ADULT_AGE && m.age <= 1.0, "{}: adult", b.name);
            assert!((m.african + m.asian + m.caucasian - 1.0).abs() < 1e-12, "{}: ethnic mix sums to 1", b.name);
        }
        let weights: Vec<f64> = a.iter().map(|b| b.params.macros.weight).collect();
        assert!(weights.contains(&0.0) && weights.contains(&1.0));
        let men = a.iter().filter(|b| b.params.macros.gender > 0.5).count();
        assert!((10..=30).contains(&men), "{men} men of 40");
    }
}
