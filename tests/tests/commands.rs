//! Every command kind: execute → undo restores the exact content hash and every non-voxel
//! field → redo re-applies exactly. History bounds, coalescing and failures.

use app::builtin::{SceneSize, default_scene};
use app::editor::Document;
use app::editor::command::{
    BrushMode, BrushShape, Command, KindSpec, MaterialSpec, Mirror, Stroke, TerrainSpec,
};
use app::editor::history::History;
use glam::{DVec3, IVec3};
use render::{Camera, RenderSettings, Sky, Sun};

/// Everything a command may change: voxels (hash), tables, camera, sun, sky, settings.
fn state(doc: &Document) -> (u64, u64, String) {
    use std::hash::{Hash, Hasher};
    let view = doc.scene.world.read();
    let mut h = std::collections::hash_map::DefaultHasher::new();
    view.materials().logical_bytes().hash(&mut h);
    (
        view.content_hash(),
        h.finish(),
        format!("{:?}", doc.scene.params),
    )
}

fn document() -> Document {
    Document::new(
        default_scene(SceneSize::Small, 2).unwrap(),
        History::default(),
    )
}

fn stroke(mode: BrushMode, shape: BrushShape, size: f64, points: &[[f64; 3]]) -> Command {
    Command::Stroke(Stroke {
        mode,
        shape,
        size,
        material: 4,
        mirror: Mirror::default(),
        points: points.iter().map(|p| DVec3::from_array(*p)).collect(),
        axis: Default::default(),
        in_selection: false,
        paint: Default::default(),
    })
}

fn every_command() -> Vec<Command> {
    let p = |x, y, z| [x, y, z];
    vec![
        stroke(
            BrushMode::Attach,
            BrushShape::Sphere,
            5.0,
            &[p(30.0, 50.0, 30.0), p(40.0, 52.0, 35.0)],
        ),
        stroke(
            BrushMode::Erase,
            BrushShape::Cube,
            3.0,
            &[p(64.0, 30.0, 64.0)],
        ),
        stroke(
            BrushMode::Paint,
            BrushShape::Cylinder,
            4.0,
            &[p(20.0, 30.0, 90.0)],
        ),
        stroke(
            BrushMode::Attach,
            BrushShape::Line,
            1.5,
            &[
                p(10.0, 55.0, 10.0),
                p(60.0, 58.0, 20.0),
                p(90.0, 50.0, 70.0),
            ],
        ),
        stroke(
            BrushMode::Attach,
            BrushShape::Box,
            1.0,
            &[p(100.0, 40.0, 100.0), p(110.0, 47.0, 104.0)],
        ),
        stroke(
            BrushMode::Attach,
            BrushShape::Voxel,
            1.0,
            &[p(1.5, 60.5, 1.5), p(2.5, 60.5, 1.5)],
        ),
        Command::Stroke(Stroke {
            mode: BrushMode::Attach,
            shape: BrushShape::Sphere,
            size: 3.0,
            material: 5,
            mirror: Mirror {
                x: true,
                y: false,
                z: true,
                centre: DVec3::new(64.0, 0.0, 64.0),
            },
            points: vec![DVec3::new(20.0, 50.0, 30.0)],
            axis: Default::default(),
            in_selection: false,
            paint: Default::default(),
        }),
        Command::FloodFill {
            start: IVec3::new(64, 0, 0),
            material: 5,
        },
        Command::AddMaterial(MaterialSpec {
            kind: KindSpec::Metal,
            param: 10,
            colour: 33,
        }),
        Command::SetMaterial {
            index: 1,
            material: MaterialSpec {
                kind: KindSpec::Dielectric,
                param: 1,
                colour: 40,
            },
        },
        Command::SetColour {
            index: 200,
            rgb: [1, 2, 3],
        },
        Command::SetParam {
            kind: KindSpec::Emissive,
            index: 5,
            value: 42.0,
        },
        Command::SetSun(Sun {
            enabled: false,
            position: DVec3::new(1.0, 500.0, 2.0),
            radius: 9.0,
            colour: [1.0, 0.5, 0.2],
            intensity: 3.0,
            animate: true,
            speed_deg_per_s: 4.0,
        }),
        Command::SetSky(Sky::Uniform {
            colour: [0.1, 0.2, 0.3],
        }),
        Command::SetCamera(Camera {
            position: DVec3::new(5.0, 90.0, 5.0),
            yaw_deg: 30.0,
            pitch_deg: -40.0,
            fov_y_deg: 70.0,
            projection: render::Projection::Orthographic { height: 40.0 },
        }),
        Command::SetSettings(RenderSettings {
            samples_per_pixel: 4,
            max_bounces: 5,
            internal_resolution: (640, 360),
            exposure: 1.5,
            sequence: render::Sequence::Sobol,
        }),
        Command::SetPalette((0..256).map(|i| [i as u8, 7, 255 - i as u8]).collect()),
        Command::GenerateTerrain(TerrainSpec {
            seed: 5,
            scale: 50.0,
            octaves: 4,
            height_range: (10, 50),
            water_level: 24,
            noise: app::editor::command::NoiseKind::OpenSimplex,
            bands: app::editor::command::Bands {
                rock_line: 0.3,
                snow_line: 0.5,
                soil_depth: 6,
            },
        }),
        Command::ImportVox {
            path: "../assets/vox/mmmm_chr_robot.vox".into(),
            offset: IVec3::new(20, 30, 20),
        },
        Command::Clear,
    ]
}

#[test]
fn every_command_undoes_and_redoes_exactly() {
    for command in every_command() {
        let mut doc = document();
        doc.folder = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
        let before = state(&doc);
        doc.execute(command.clone())
            .unwrap_or_else(|e| panic!("{command:?}: {e:#}"));
        let after = state(&doc);
        assert_ne!(before, after, "{command:?} changed nothing");
        doc.world_check();
        doc.undo().unwrap();
        assert_eq!(state(&doc), before, "undo of {command:?}");
        doc.world_check();
        doc.redo().unwrap();
        assert_eq!(state(&doc), after, "redo of {command:?}");
        doc.undo().unwrap();
        assert_eq!(state(&doc), before, "second undo of {command:?}");
        assert_eq!((doc.history.undo_len(), doc.history.redo_len()), (0, 1));
    }
}

trait Check {
    fn world_check(&self);
}
impl Check for Document {
    fn world_check(&self) {
        self.scene.world.read().validate().unwrap();
    }
}

#[test]
fn failed_commands_change_nothing() {
    let mut doc = document();
    doc.execute(stroke(
        BrushMode::Attach,
        BrushShape::Sphere,
        4.0,
        &[[50.0, 50.0, 50.0]],
    ))
    .unwrap();
    let before = state(&doc);
    let bad = [
        Command::Stroke(Stroke {
            material: 200,
            ..match stroke(
                BrushMode::Attach,
                BrushShape::Sphere,
                4.0,
                &[[5.0, 5.0, 5.0]],
            ) {
                Command::Stroke(s) => s,
                _ => unreachable!(),
            }
        }),
        stroke(
            BrushMode::Attach,
            BrushShape::Sphere,
            -1.0,
            &[[5.0, 5.0, 5.0]],
        ),
        stroke(BrushMode::Attach, BrushShape::Sphere, 2.0, &[]),
        stroke(
            BrushMode::Attach,
            BrushShape::Sphere,
            2.0,
            &[[f64::NAN, 1.0, 1.0]],
        ),
        Command::FloodFill {
            start: IVec3::new(5, 63, 5),
            material: 1,
        }, // empty voxel
        Command::FloodFill {
            start: IVec3::new(500, 0, 0),
            material: 1,
        },
        Command::SetPalette(vec![[1, 2, 3]; 3]),
        Command::SetMaterial {
            index: 99,
            material: MaterialSpec {
                kind: KindSpec::Metal,
                param: 0,
                colour: 1,
            },
        },
        Command::SetParam {
            kind: KindSpec::Metal,
            index: 3,
            value: 7.0,
        },
        Command::SetCamera(Camera {
            position: DVec3::ZERO,
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            fov_y_deg: 0.0,
            projection: render::Projection::Perspective,
        }),
        Command::GenerateTerrain(TerrainSpec {
            seed: 1,
            scale: 10.0,
            octaves: 40,
            height_range: (1, 5),
            water_level: 0,
            noise: Default::default(),
            bands: Default::default(),
        }),
        Command::ImportVox {
            path: "no/such.vox".into(),
            offset: IVec3::ZERO,
        },
    ];
    for command in bad {
        assert!(
            doc.execute(command.clone()).is_err(),
            "{command:?} accepted"
        );
        assert_eq!(state(&doc), before, "{command:?} changed the document");
        assert_eq!(doc.history.undo_len(), 1, "{command:?} touched the history");
    }
}

#[test]
fn slider_drags_coalesce_and_new_commands_drop_redo() {
    let mut doc = document();
    let before = state(&doc);
    for v in 0..20u8 {
        doc.execute(Command::SetColour {
            index: 7,
            rgb: [v, v, v],
        })
        .unwrap();
    }
    assert_eq!(doc.history.undo_len(), 1, "one step for the whole drag");
    doc.execute(Command::SetColour {
        index: 8,
        rgb: [1, 1, 1],
    })
    .unwrap();
    assert_eq!(
        doc.history.undo_len(),
        2,
        "another property is another step"
    );
    doc.undo().unwrap();
    doc.undo().unwrap();
    assert_eq!(state(&doc), before);
    assert_eq!(doc.history.redo_len(), 2);
    doc.execute(stroke(
        BrushMode::Attach,
        BrushShape::Voxel,
        1.0,
        &[[3.0, 62.0, 3.0]],
    ))
    .unwrap();
    assert_eq!(
        doc.history.redo_len(),
        0,
        "a new command drops the redo branch"
    );
    assert!(doc.redo().is_err());
    assert_eq!(doc.history.labels(), vec!["Attach Voxel stroke (1 points)"]);
}

#[test]
fn history_memory_is_bounded_and_reports_drops() {
    let scene = default_scene(SceneSize::Small, 2).unwrap();
    let mut doc = Document::new(scene, History::with_budget(100_000));
    let mut dropped = 0;
    for i in 0..40 {
        let x = 10.0 + (i % 10) as f64 * 11.0;
        dropped += doc
            .execute(stroke(
                BrushMode::Attach,
                BrushShape::Sphere,
                6.0,
                &[[x, 45.0, 20.0 + (i / 10) as f64 * 25.0]],
            ))
            .unwrap()
            .dropped;
    }
    assert!(dropped > 0, "the budget forces drops");
    assert_eq!(doc.history.dropped(), dropped);
    assert!(doc.history.bytes() <= 100_000, "{}", doc.history.bytes());
    assert_eq!(doc.history.undo_len() as u64, 40 - dropped);
    // Everything left can still be undone.
    while doc.history.undo_len() > 0 {
        doc.undo().unwrap();
    }
    doc.scene.world.read().validate().unwrap();
}

/// Every solid voxel's material as it looks (kind, parameter value, colour), not its index.
fn appearance(doc: &Document) -> Vec<(IVec3, String)> {
    let view = doc.scene.world.read();
    let table = view.materials();
    let mut out = Vec::new();
    view.for_each_brick(|b, mask, _| {
        for bit in mask.ones() {
            let v =
                b.as_ivec3() * 8 + IVec3::new(bit as i32 % 8, bit as i32 / 8 % 8, bit as i32 / 64);
            let m = table.get(view.voxel(v).unwrap().unwrap()).unwrap();
            let param = table.param(m.kind, m.param).unwrap();
            out.push((
                v,
                format!("{:?} {param} {:?}", m.kind, table.colour(m.colour)),
            ));
        }
    });
    out.sort_by_key(|(v, _)| (v.x, v.y, v.z));
    out
}

#[test]
fn removing_unused_materials_keeps_every_voxels_look_and_undoes_exactly() {
    let mut doc = document();
    let spec = |colour| MaterialSpec {
        kind: KindSpec::Metal,
        param: 7,
        colour,
    };
    doc.execute(Command::AddMaterial(spec(50))).unwrap();
    doc.execute(Command::AddMaterial(spec(90))).unwrap();
    let len = doc.scene.world.materials().len();
    // Material 1 of the terrain is left unused, and the last one paints a ball.
    let used_by_terrain: Vec<u8> = {
        let view = doc.scene.world.read();
        let mut seen = [false; 256];
        view.for_each_brick(|_, mask, mats| match mats {
            brickmap::BrickMaterials::Uniform(m) => seen[m as usize] = true,
            brickmap::BrickMaterials::PerVoxel(v) => v[..mask.count() as usize]
                .iter()
                .for_each(|m| seen[*m as usize] = true),
        });
        (0..len as u8).filter(|m| seen[*m as usize]).collect()
    };
    let mut paint = stroke(
        BrushMode::Paint,
        BrushShape::Sphere,
        9.0,
        &[[64.0, 30.0, 64.0]],
    );
    if let Command::Stroke(s) = &mut paint {
        s.material = (len - 1) as u8;
    }
    doc.execute(paint).unwrap();
    let unused = len - 1 - used_by_terrain.len();
    assert!(unused >= 1, "the test leaves a material unused");
    let before = (state(&doc), appearance(&doc));
    doc.execute(Command::RemoveUnusedMaterials).unwrap();
    assert_eq!(doc.scene.world.materials().len(), len - unused);
    assert_eq!(appearance(&doc), before.1, "every voxel looks as before");
    doc.scene.world.read().validate().unwrap();
    let after = state(&doc);
    doc.undo().unwrap();
    assert_eq!((state(&doc), appearance(&doc)), before, "undo");
    doc.redo().unwrap();
    assert_eq!(state(&doc), after, "redo");
    // Nothing left to remove: refused, nothing changes.
    let steps = doc.history.undo_len();
    assert!(doc.execute(Command::RemoveUnusedMaterials).is_err());
    assert_eq!((state(&doc), doc.history.undo_len()), (after, steps));
}

#[test]
fn terrain_bands_decide_the_surface_material() {
    let mut doc = document();
    let spec = |rock_line, snow_line| TerrainSpec {
        bands: app::editor::command::Bands {
            rock_line,
            snow_line,
            soil_depth: 3,
        },
        ..TerrainSpec::for_size((128, 64, 128))
    };
    doc.execute(Command::GenerateTerrain(spec(0.0, 0.0)))
        .unwrap();
    // Every column was counted for the progress shown, which is over now.
    assert_eq!(doc.progress.done(), 16 * 16, "the grid's brick columns");
    assert_eq!(doc.progress.fraction(), None);
    let view = doc.scene.world.read();
    let table = view.materials();
    let (mut snow, mut other) = (0, 0);
    for x in 0..128 {
        for z in 0..128 {
            let top = (0..64)
                .rev()
                .find_map(|y| view.voxel(IVec3::new(x, y, z)).unwrap())
                .unwrap();
            let m = table.get(top).unwrap();
            let colour = table.colour(m.colour);
            if m.kind == brickmap::MaterialKind::Dielectric || colour == [218, 202, 150] {
                continue; // water, or the sand at its edge
            }
            if colour == [240, 244, 250] {
                snow += 1;
            } else {
                other += 1;
            }
        }
    }
    assert!(snow > 1000 && other == 0, "snow {snow}, other {other}");
    drop(view);
    let snowy = doc.scene.world.read().content_hash();
    doc.execute(Command::GenerateTerrain(spec(0.62, 0.86)))
        .unwrap();
    assert_ne!(doc.scene.world.read().content_hash(), snowy);
}

/// Extrude (push-pull) and plane fill on a platform with a strip of another material: the
/// region, the columns' materials, push-in, same-material regions, the plane's extent, the
/// refusals; each one step, undone exactly.
#[test]
fn extrude_and_plane_fill_change_exactly_their_region() {
    use app::scene::Scene;
    use app::selection::SelectOp;
    let mut doc = Document::new(
        Scene::empty(brickmap::GridDims::new(4, 4, 4).unwrap(), 2).unwrap(),
        History::default(),
    );
    doc.execute(Command::AddMaterial(MaterialSpec {
        kind: KindSpec::Lambertian,
        param: 0,
        colour: 9,
    }))
    .unwrap();
    let mut fill = |lo: [i32; 3], hi: [i32; 3], m: u8| {
        doc.execute(Command::Select(SelectOp::Replace {
            min: IVec3::from_array(lo),
            max: IVec3::from_array(hi),
        }))
        .unwrap();
        doc.execute(Command::FillSelection(m)).unwrap();
        doc.execute(Command::Select(SelectOp::None)).unwrap();
    };
    // A platform 8 × 4 × 8, its top's first two rows (x 4..=5) of material 1.
    fill([4, 2, 4], [11, 5, 11], 0);
    fill([4, 5, 4], [5, 5, 11], 1);
    let at = |doc: &Document, x, y, z| doc.scene.world.read().voxel(IVec3::new(x, y, z)).unwrap();
    let before = state(&doc);
    let steps = doc.history.undo_len();
    let extrude = |distance, same_material| Command::Extrude {
        voxel: IVec3::new(8, 5, 8),
        normal: IVec3::Y,
        distance,
        same_material,
    };
    // Up by 3: every column of the top grows in its own material.
    doc.execute(extrude(3, false)).unwrap();
    for x in 0..32 {
        for z in 0..32 {
            for y in 6..=9 {
                let on = (4..=11).contains(&x) && (4..=11).contains(&z) && y <= 8;
                let want = on.then_some(if x <= 5 { 1 } else { 0 });
                assert_eq!(at(&doc, x, y, z), want, "({x}, {y}, {z})");
            }
        }
    }
    assert_eq!(doc.history.undo_steps().last().unwrap().changed_voxels, 192);
    doc.undo().unwrap();
    assert_eq!(state(&doc), before);
    // The same material only: the strip stays.
    doc.execute(extrude(2, true)).unwrap();
    assert_eq!(
        doc.history.undo_steps().last().unwrap().changed_voxels,
        6 * 8 * 2
    );
    assert_eq!(at(&doc, 5, 6, 8), None);
    assert_eq!(at(&doc, 6, 7, 8), Some(0));
    doc.undo().unwrap();
    // Pushed in by 2: the top two layers of the region go.
    doc.execute(extrude(-2, false)).unwrap();
    for (y, want) in [(5, None), (4, None), (3, Some(0))] {
        assert_eq!(at(&doc, 8, y, 8), want, "y {y}");
    }
    assert_eq!(doc.history.undo_steps().last().unwrap().changed_voxels, 128);
    doc.undo().unwrap();
    assert_eq!(state(&doc), before);
    // Plane fill in front of the top: the whole empty layer y = 6 of the grid.
    doc.execute(Command::PlaneFill {
        voxel: IVec3::new(8, 5, 8),
        normal: IVec3::Y,
        material: 1,
    })
    .unwrap();
    assert_eq!(
        doc.history.undo_steps().last().unwrap().changed_voxels,
        32 * 32
    );
    assert_eq!((at(&doc, 0, 6, 31), at(&doc, 0, 7, 31)), (Some(1), None));
    doc.undo().unwrap();
    assert_eq!(
        (state(&doc), doc.history.undo_len()),
        (before.clone(), steps)
    );
    // Refusals change nothing: no distance, a covered face, a normal that is no axis.
    for c in [
        extrude(0, false),
        Command::Extrude {
            voxel: IVec3::new(8, 3, 8),
            normal: IVec3::X,
            distance: 1,
            same_material: false,
        },
        Command::Extrude {
            voxel: IVec3::new(8, 5, 8),
            normal: IVec3::new(1, 1, 0),
            distance: 1,
            same_material: false,
        },
    ] {
        assert!(doc.execute(c.clone()).is_err(), "{c:?}");
        assert_eq!(
            (state(&doc), doc.history.undo_len()),
            (before.clone(), steps)
        );
    }
}

/// Stamp: the clipboard turned (by an independent formula: a quarter turn about y maps
/// (x, y, z) in a box of size s to (z, y, s.x − 1 − x)) and put down at each place, later
/// stamps winning, voxel by voxel against the grid before; undo exact; refusals change
/// nothing.
#[test]
fn stamps_put_the_turned_clipboard_down_at_each_place() {
    let (lo, hi) = (IVec3::new(40, 20, 50), IVec3::new(47, 34, 53));
    // A scene with something of several materials in the box, the box copied (after a
    // stamp with nothing copied is refused).
    let copied = || {
        let mut doc = document();
        doc.execute(stroke(
            BrushMode::Attach,
            BrushShape::Sphere,
            3.0,
            &[[43.0, 30.0, 51.0]],
        ))
        .unwrap();
        let empty_clipboard = doc
            .execute(Command::Stamp {
                at: vec![IVec3::new(5, 40, 5)],
                quarters: 0,
            })
            .unwrap_err();
        assert!(empty_clipboard.is_no_op(), "{empty_clipboard}");
        doc.execute(Command::Select(app::selection::SelectOp::Replace {
            min: lo,
            max: hi,
        }))
        .unwrap();
        doc.execute(Command::Copy).unwrap();
        doc
    };
    let doc = copied();
    let dims = doc.scene.world.dims().voxels();
    let clip: Vec<(IVec3, u8)> = {
        let view = doc.scene.world.read();
        every(lo, hi)
            .filter_map(|v| view.voxel(v).unwrap().map(|m| (v - lo, m)))
            .collect()
    };
    assert!(clip.len() > 50, "the copy holds {} voxels", clip.len());
    let size = hi - lo + 1;
    for quarters in [0, 1, 3] {
        let mut doc = copied();
        let before = state(&doc);
        let old = {
            let view = doc.scene.world.read();
            every(IVec3::ZERO, dims - 1)
                .map(|v| view.voxel(v).unwrap())
                .collect::<Vec<_>>()
        };
        // Two overlapping stamps, one past the grid's side.
        let at = vec![
            IVec3::new(70, 36, 70),
            IVec3::new(73, 38, 72),
            IVec3::new(dims.x - 3, 40, 10),
        ];
        doc.execute(Command::Stamp {
            at: at.clone(),
            quarters,
        })
        .unwrap();
        let mut want: std::collections::HashMap<IVec3, u8> = Default::default();
        for a in &at {
            for (p, m) in &clip {
                let (mut p, mut s) = (*p, size);
                for _ in 0..quarters {
                    p = IVec3::new(p.z, p.y, s.x - 1 - p.x);
                    s = IVec3::new(s.z, s.y, s.x);
                }
                want.insert(*a + p, *m);
            }
        }
        let view = doc.scene.world.read();
        for (v, was) in every(IVec3::ZERO, dims - 1).zip(&old) {
            let expected = want.get(&v).copied().or(*was);
            assert_eq!(view.voxel(v).unwrap(), expected, "{quarters} turns, at {v}");
        }
        drop(view);
        let after = state(&doc);
        doc.undo().unwrap();
        assert_eq!(state(&doc), before, "{quarters}: undo");
        doc.redo().unwrap();
        assert_eq!(state(&doc), after, "{quarters}: redo");
        let too_many = doc
            .execute(Command::Stamp {
                at: vec![IVec3::ZERO; app::editor::stamp::MAX_STAMPS + 1],
                quarters,
            })
            .unwrap_err();
        assert!(matches!(too_many, app::editor::EditError::Invalid(_)));
        assert_eq!(state(&doc), after);
    }
}

fn every(lo: IVec3, hi: IVec3) -> impl Iterator<Item = IVec3> {
    (lo.x..=hi.x).flat_map(move |x| {
        (lo.y..=hi.y).flat_map(move |y| (lo.z..=hi.z).map(move |z| IVec3::new(x, y, z)))
    })
}
