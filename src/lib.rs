//! grade3d — automated 3D garment grading.
//!
//! Pure geometry core (no I/O, no async, no GPU types) with a thin HTTP
//! shell. Data flow and module map: `ARCHITECTURE.md`. Equations cite the
//! papers in `../shared/seeds/` (seed 000: Wang, Wang & Yuen 2002,
//! "Feature based 3D garment design through 2D sketches").

pub mod body;
pub mod collide;
pub mod geom;
pub mod io;
pub mod mannequin;
pub mod pattern;
pub mod pipeline;
pub mod refine;
pub mod service;
pub mod template;
