//! Scenes in and out: the built-in and seed scenes, scene files and `--set` values
//! (bad input, its messages, validation, a property-based test), the topology the
//! builders make, OBJ meshes imported as cloth and cloth exported as OBJ. The few
//! tests that run the `cloth` binary need the `app` feature.

#[cfg(feature = "app")]
#[path = "../binary/mod.rs"]
mod binary;
#[path = "../common/mod.rs"]
mod common;

mod bad_scenes;
mod export_obj;
mod input_validation;
mod materials;
mod mesh_import;
mod scene_messages;
mod scene_proptest;
mod seed_scenes;
mod topology;
