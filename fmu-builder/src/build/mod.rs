//! The driver: runs the stages for one spec. `mounted` builds bodies with at least one mount or
//! a reduction of the coupled model, `free_floating` bodies without mounts, `sweep` compares
//! reduced orders side by side.

pub mod free_floating;
pub mod mounted;
pub mod sweep;
