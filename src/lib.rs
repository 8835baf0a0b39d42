//! grade3d — automated 3D garment grading.
//!
//! The shell around [`grade3d_core`] (the pure geometry core, re-exported
//! here module by module so that `grade3d::geom::…` and the like keep
//! their paths): glTF and landmark input ([`io`]), the wgpu depth-map
//! renderer and the per-body obstacle cache ([`collide`]), the MakeHuman
//! data generator ([`makehuman`]) and the HTTP service ([`service`]). Data
//! flow and module map: `ARCHITECTURE.md`.

pub use grade3d_core::{body, geom, mannequin, pattern, pipeline, refine, template};

pub mod collide;
pub mod io;
pub mod makehuman;
pub mod service;
