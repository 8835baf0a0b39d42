//! Parsing and writing of external formats (glTF, landmark JSON).
//! Every reader validates and returns typed errors; none panics on input.
pub mod gltf;
pub mod landmarks;
pub mod obj;
