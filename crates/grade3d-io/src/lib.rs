//! Parsing and writing of external formats (glTF, landmark JSON).
//! Every reader validates and returns typed errors; none panics on input.
//!
//! The `grade3d-io` crate (issue #16): parsers and writers of bytes, on
//! the core's types (named here as `crate::geom` and `crate::body`).

use grade3d_core::{body, geom};

pub mod garment;
pub mod gltf;
pub mod landmarks;
pub mod obj;
