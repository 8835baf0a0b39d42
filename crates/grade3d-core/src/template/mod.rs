//! Garment feature templates (seed 000 §3–4): the document format, encoding
//! a garment mesh on a reference body, decoding it onto any feature human
//! model (Eq. 1, Eq. 2, Eq. 5), edge profiles, sketch edits (§4: node moves
//! and profiles from 2D strokes, applied to a template under seed 002's
//! constraints: `edit`), and the built-in library (`library`; its styles
//! drawn as curves: `drawn`).

pub mod codec;
pub mod drawn;
pub mod edit;
pub mod format;
pub mod from_curves;
pub mod from_garment;
pub mod garment_panels;
pub mod girth;
pub mod library;
pub mod profile;
pub mod sketch;
pub mod topology;
