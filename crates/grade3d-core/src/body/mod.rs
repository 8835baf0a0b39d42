//! Feature human models (seed 000 §3.1–3.2): body meshes with feature
//! curves, feature points and local frames.

pub mod contact;
pub mod derive;
pub mod ease;
pub mod feature;
pub mod frame;
pub mod measure;
pub mod vocab;
