//! Refinement of the coarse garment mesh (seed 000 §5): modified
//! variational subdivision with collision avoidance.

pub mod clear;
pub mod collision;
pub mod lineage;
pub mod subdivide;
pub mod symmetry;
