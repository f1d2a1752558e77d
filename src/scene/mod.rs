//! Loading: glTF scenes, environment maps and IES photometric profiles, each with clear errors.
pub mod ies;
