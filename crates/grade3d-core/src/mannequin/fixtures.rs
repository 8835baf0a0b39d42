//! The test-fixture bodies: eight adults spanning gender, build, stature
//! and race, built from the embedded model. `cargo xtask data fixtures`
//! writes each as GLB + landmarks JSON under `fixtures/bodies/`, and the
//! ASTM D5585 size mannequins under `fixtures/astm/`.

use super::model::{MacroParams, MannequinParams};

/// A named fixture body.
#[derive(Debug, Clone, PartialEq)]
pub struct FixtureBody {
    /// File stem.
    pub name: &'static str,
    /// Model parameters.
    pub params: MannequinParams,
}

fn body(
    name: &'static str,
    gender: f64,
    age: f64,
    muscle: f64,
    weight: f64,
    height: f64,
    race: [f64; 3],
) -> FixtureBody {
    FixtureBody {
        name,
        params: MannequinParams {
            macros: MacroParams {
                gender,
                age,
                muscle,
                weight,
                height,
                proportions: 0.5,
                african: race[0],
                asian: race[1],
                caucasian: race[2],
            },
            modifiers: Default::default(),
        },
    }
}

/// The eight fixture bodies.
pub fn fixture_bodies() -> Vec<FixtureBody> {
    vec![
        body("female-slim-short-asian", 0.0, 0.5, 0.5, 0.1, 0.2, [0.0, 1.0, 0.0]),
        body("female-average-caucasian", 0.0, 0.5, 0.5, 0.5, 0.5, [0.0, 0.0, 1.0]),
        body("female-heavy-tall-african", 0.0, 0.5, 0.5, 0.95, 0.8, [1.0, 0.0, 0.0]),
        body("female-older-mixed", 0.0, 0.8, 0.4, 0.7, 0.4, [0.3, 0.3, 0.4]),
        body("male-slim-tall-caucasian", 1.0, 0.5, 0.5, 0.15, 0.9, [0.0, 0.0, 1.0]),
        body("male-average-asian", 1.0, 0.5, 0.5, 0.5, 0.4, [0.0, 1.0, 0.0]),
        body("male-heavy-short-african", 1.0, 0.5, 0.3, 1.0, 0.15, [1.0, 0.0, 0.0]),
        body("male-muscular-mixed", 1.0, 0.6, 0.9, 0.6, 0.6, [0.4, 0.2, 0.4]),
    ]
}
