//! Sewing patterns from the refined garment (seed 000 §6; issue #5): cut
//! into panels along the seams ([`panels`]), flatten each ([`flatten`]),
//! build pattern pieces with sew and cut lines, notches and grain
//! ([`assemble`]), check their internal lines ([`lines`]) and their thread strain
//! ([`fabric`]), flatten a mirror pair's second piece as the mirror image of its first
//! ([`mirror`]), grade them
//! across sizes ([`grade`]), true their nests at the corners ([`true_up`]) and export them ([`export`]).

pub mod assemble;
pub mod darts;
pub mod export;
pub mod fabric;
pub mod flatten;
pub mod garment;
pub mod grade;
pub mod lines;
pub mod mirror;
pub mod panels;
pub mod piece;
pub mod true_up;
