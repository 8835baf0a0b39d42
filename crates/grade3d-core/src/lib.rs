//! grade3d's pure core: data in, data out (issue #16).
//!
//! Geometry ([`geom`]), feature bodies ([`body`]), the embedded parametric
//! mannequin and its fit to size charts ([`mannequin`]), garment feature
//! templates ([`template`]), refinement by modified variational
//! subdivision with collision against depth maps given to it ([`refine`],
//! [`collide`]), flattening and sewing patterns with their exports as bytes
//! ([`pattern`]), and one grade end to end ([`pipeline`]). No async
//! runtime, HTTP, GPU, database, files or threads of its own: its
//! `Cargo.toml` shows what it may touch (rayon's pool is the one thread
//! budget it shares with its caller). Equations cite the papers in
//! `../shared/seeds/` (seed 000: Wang, Wang & Yuen 2002, "Feature based 3D
//! garment design through 2D sketches"). Module map: `ARCHITECTURE.md`.

pub mod body;
pub mod collide;
pub mod geom;
pub mod mannequin;
pub mod pattern;
pub mod pipeline;
pub mod refine;
pub mod report;
pub mod scan;
pub mod template;
