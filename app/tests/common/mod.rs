//! Helpers the format tests share: a .vox file from parts, and importing one.
#![allow(dead_code)] // each test file uses part of it

use app::Scene;
use app::formats::vox;
use dot_vox::{DEFAULT_INDEX_MAP, DEFAULT_PALETTE, DotVoxData, Layer, Material, Model, SceneNode};
use std::path::Path;

/// The bytes of a .vox file with the default palette: models, MATL chunks, scene graph and
/// layers as given.
pub fn vox_bytes(
    models: Vec<Model>,
    materials: Vec<Material>,
    scenes: Vec<SceneNode>,
    layers: Vec<Layer>,
) -> Vec<u8> {
    let data = DotVoxData {
        version: 150,
        index_map: DEFAULT_INDEX_MAP.to_vec(),
        models,
        palette: DEFAULT_PALETTE.to_vec(),
        materials,
        scenes,
        layers,
    };
    let mut bytes = Vec::new();
    data.write_vox(&mut bytes).unwrap();
    bytes
}

/// Imports .vox bytes as a new scene with the default options (`name` is the file name the
/// messages use); panics on an error.
pub fn import(bytes: &[u8], name: &str) -> (Scene, vox::ImportReport) {
    vox::import_bytes(bytes, Path::new(name), &vox::ImportOptions::default(), 1).unwrap()
}
