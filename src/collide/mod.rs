//! Collision avoidance against the body (seed 000 §5.4): depth maps
//! rendered offscreen with wgpu ([`render`], the only GPU module), cached
//! per body ([`cache`]); the maps' inside test of Eq. (13) and the
//! [`Obstacle`] are the core's ([`depth`]).

pub use grade3d_core::collide::{depth, Obstacle};

pub mod cache;
pub mod render;
