//! Sponge `.schem` files of versions 1, 2 and 3 written by other tools (`assets/schem/`, see
//! SOURCES.md): each imports through the block table (blocks it lacks reported by name,
//! block entities and entities reported as left out); import → export → import keeps every
//! voxel's material; the exported file is read by nbtlib (an independent NBT reader, PyPI)
//! with the same size and block counts; damaged and hostile files give an error or a valid
//! scene, never a panic.

use super::mesh::{script, tools};
use super::*;
use app::formats::schem::{self, BlockTable, nbt};
use std::collections::BTreeMap;

fn files() -> Vec<PathBuf> {
    asset_files("schem", "schem", 5)
}

#[test]
fn schematics_of_every_version_import_and_round_trip_exactly() {
    let d = scratch("schem");
    let table = BlockTable::builtin();
    let tools = tools();
    let mut versions = std::collections::BTreeSet::new();
    for file in files() {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let bytes = std::fs::read(&file).unwrap();
        let (scene, report) = schem::import(&bytes, &file, &table, 2).unwrap();
        versions.insert(report.version);
        let view = scene.world.read();
        view.validate().unwrap();
        assert!(report.voxels > 0, "{name}");
        assert_eq!(view.solid_count(), report.voxels, "{name}");
        assert!(report.size.cmple(view.dims().voxels()).all(), "{name}");
        // Most blocks are in the table.
        let unknown: u64 = report.unknown.values().sum();
        assert!(unknown * 2 < report.voxels, "{name}: {:?}", report.unknown);
        drop(view);
        let out = d.join(&name);
        let written = schem::export(&scene, &out, &table).unwrap();
        assert_eq!(written.voxels, report.voxels, "{name}");
        let again_bytes = std::fs::read(&out).unwrap();
        let (again, again_report) = schem::import(&again_bytes, &out, &table, 2).unwrap();
        assert_eq!(again_report.version, 2);
        // Every voxel keeps its material, but those of blocks the table lacks: their
        // unknown material is no block, so it is written as the nearest one (reported).
        let unknown = [214, 88, 214];
        let (a, b) = (content(&scene.world), content(&again.world));
        assert_eq!(a.len(), b.len(), "{name}");
        let mut odd = 0;
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.0, y.0, "{name}");
            if x.3 == unknown {
                odd += 1;
            } else {
                assert_eq!(x, y, "{name}");
            }
        }
        assert_eq!(odd > 0, written.as_nearest > 0, "{name}");
        assert_eq!(odd as u64, report.unknown.values().sum::<u64>(), "{name}");
        // nbtlib reads the export: its size and the count of each block.
        if let Some(tools) = &tools {
            let run = std::process::Command::new(tools.join("venv/bin/python"))
                .arg(script("schem_read.py"))
                .arg(&out)
                .output()
                .unwrap();
            assert!(
                run.status.success(),
                "{}",
                String::from_utf8_lossy(&run.stderr)
            );
            let v: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
            assert_eq!(v["version"], 2);
            let size = again_report.size;
            assert_eq!(v["size"], serde_json::json!([size.x, size.y, size.z]));
            let blocks: BTreeMap<String, u64> = v["blocks"]
                .as_object()
                .unwrap()
                .iter()
                .map(|(k, n)| (k.clone(), n.as_u64().unwrap()))
                .collect();
            let air = blocks.get("minecraft:air").copied().unwrap_or(0);
            assert_eq!(
                air + report.voxels,
                (size.x * size.y * size.z) as u64,
                "{name}"
            );
            assert_eq!(blocks.values().sum::<u64>() - air, report.voxels, "{name}");
        }
    }
    assert_eq!(versions.into_iter().collect::<Vec<_>>(), [1, 2, 3]);
}

/// A version 2 schematic of `blocks` (state, x, y, z) in a `size` box, with one block entity.
fn made(size: IVec3, blocks: &[(&str, IVec3)]) -> Vec<u8> {
    let mut names = vec!["minecraft:air".to_string()];
    let mut ids = vec![0u8; (size.x * size.y * size.z) as usize];
    for (state, p) in blocks {
        let id = match names.iter().position(|n| n == state) {
            Some(k) => k,
            None => {
                names.push(state.to_string());
                names.len() - 1
            }
        };
        ids[(p.x + p.z * size.x + p.y * size.x * size.z) as usize] = id as u8;
    }
    let palette = names
        .iter()
        .enumerate()
        .map(|(k, n)| (n.clone(), nbt::Tag::Int(k as i32)))
        .collect();
    let mut root = BTreeMap::new();
    root.insert("Version".to_string(), nbt::Tag::Int(2));
    root.insert("Width".to_string(), nbt::Tag::Short(size.x as i16));
    root.insert("Height".to_string(), nbt::Tag::Short(size.y as i16));
    root.insert("Length".to_string(), nbt::Tag::Short(size.z as i16));
    root.insert("Palette".to_string(), nbt::Tag::Compound(palette));
    root.insert("BlockData".to_string(), nbt::Tag::ByteArray(ids));
    root.insert(
        "BlockEntities".to_string(),
        nbt::Tag::List(10, vec![nbt::Tag::Compound(BTreeMap::new())]),
    );
    nbt::write("Schematic", &nbt::Tag::Compound(root))
}

#[test]
fn blocks_become_the_tables_materials_and_what_is_left_out_is_reported() {
    let table = BlockTable::builtin();
    let bytes = made(
        IVec3::new(3, 2, 2),
        &[
            ("minecraft:stone", IVec3::new(0, 0, 0)),
            ("minecraft:glass", IVec3::new(1, 0, 0)),
            ("minecraft:gold_block", IVec3::new(2, 0, 1)),
            ("minecraft:sea_lantern", IVec3::new(0, 1, 1)),
            (
                "minecraft:oak_stairs[facing=east,half=bottom]",
                IVec3::new(1, 1, 1),
            ),
            ("minecraft:unobtainium", IVec3::new(2, 1, 0)),
            ("minecraft:cave_air", IVec3::new(2, 1, 1)),
        ],
    );
    let (scene, r) = schem::import(&bytes, Path::new("made.schem"), &table, 1).unwrap();
    assert_eq!(r.voxels, 6);
    assert_eq!(r.block_entities, 1);
    assert_eq!(
        r.unknown,
        BTreeMap::from([("minecraft:unobtainium".to_string(), 1)])
    );
    assert_eq!(
        r.derived,
        BTreeMap::from([(
            "minecraft:oak_stairs".to_string(),
            "minecraft:oak_planks".to_string()
        )])
    );
    let kinds: Vec<(IVec3, MaterialKind)> = resolved(&scene.world)
        .into_iter()
        .map(|(p, k, _, _)| (p, k))
        .collect();
    assert_eq!(
        kinds,
        vec![
            (IVec3::new(0, 0, 0), MaterialKind::Lambertian),
            (IVec3::new(0, 1, 1), MaterialKind::Emissive),
            (IVec3::new(1, 0, 0), MaterialKind::Dielectric),
            (IVec3::new(1, 1, 1), MaterialKind::Lambertian),
            (IVec3::new(2, 0, 1), MaterialKind::Metal),
            (IVec3::new(2, 1, 0), MaterialKind::Lambertian),
        ]
    );
    // An edited table changes what a block is; a bad one is refused by name.
    let edited = schem::BUILTIN_BLOCKS.replace(
        "(\"minecraft:stone\", (kind: Lambertian, colour: (125, 125, 125)))",
        "(\"minecraft:stone\", (kind: Metal, value: 0.5, colour: (125, 125, 125)))",
    );
    let edited = BlockTable::parse(&edited).unwrap();
    let (scene, _) = schem::import(&bytes, Path::new("made.schem"), &edited, 1).unwrap();
    assert_eq!(resolved(&scene.world)[0].1, MaterialKind::Metal);
    let bad = schem::BUILTIN_BLOCKS.replace("value: 1.33", "value: 9.0");
    assert!(
        BlockTable::parse(&bad)
            .unwrap_err()
            .contains("minecraft:water")
    );
}

#[test]
fn damaged_and_hostile_schematics_are_refused_without_a_panic() {
    let table = BlockTable::builtin();
    let path = Path::new("hostile.schem");
    for file in files() {
        let bytes = std::fs::read(&file).unwrap();
        for cut in (0..bytes.len()).step_by((bytes.len() / 61).max(1)) {
            assert!(
                schem::import(&bytes[..cut], path, &table, 1).is_err(),
                "cut {cut}"
            );
        }
        // Mutations of the inflated NBT (read as is when not gzip): an error or a scene.
        let mut raw = Vec::new();
        std::io::Read::read_to_end(&mut flate2::read::GzDecoder::new(&bytes[..]), &mut raw)
            .unwrap();
        for m in mutations(&raw, 300, 0x2545_f491) {
            if let Ok((scene, r)) = schem::import(&m, path, &table, 1) {
                scene.world.read().validate().unwrap();
                assert_eq!(scene.world.read().solid_count(), r.voxels);
            }
        }
    }
    // Block data shorter than the size, an index past the palette, a future version.
    let ok = made(IVec3::new(2, 1, 1), &[("minecraft:stone", IVec3::ZERO)]);
    let short = made(IVec3::new(2, 1, 1), &[]);
    let (_, mut tag) = nbt::read(&short).unwrap();
    if let nbt::Tag::Compound(c) = &mut tag {
        c.insert("BlockData".into(), nbt::Tag::ByteArray(vec![0]));
    }
    let e = schem::import(&nbt::write("Schematic", &tag), path, &table, 1)
        .map(|_| ())
        .unwrap_err();
    assert!(
        e.to_string().contains("holds 1 blocks; the size says 2"),
        "{e}"
    );
    if let nbt::Tag::Compound(c) = &mut tag {
        c.insert("BlockData".into(), nbt::Tag::ByteArray(vec![0, 9]));
    }
    let e = schem::import(&nbt::write("Schematic", &tag), path, &table, 1)
        .map(|_| ())
        .unwrap_err();
    assert!(e.to_string().contains("palette index 9"), "{e}");
    if let nbt::Tag::Compound(c) = &mut tag {
        c.insert("Version".into(), nbt::Tag::Int(4));
    }
    let e = schem::import(&nbt::write("Schematic", &tag), path, &table, 1)
        .map(|_| ())
        .unwrap_err();
    assert!(e.to_string().contains("version 4"), "{e}");
    assert!(schem::import(&ok, path, &table, 1).is_ok());
}
