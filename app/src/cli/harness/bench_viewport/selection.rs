//! `bench-viewport --edits`, the selection and the modelling tools on a 256 × 64 × 256
//! selection of the default scene: each operation applied (timed), shown (timed, to the first
//! frame with all of it uploaded) and undone (not timed), several times.

use super::{edit_request, frames_until_shown, objects};
use anyhow::Result;
use render::viewport::Viewport;

/// A 256 × 64 × 256 selection of the default scene (through its surface): select, copy,
/// paste, move by a voxel and by a brick, turn, mirror, four stamps of the copy, the magic
/// wand, an extrude of the top face, a gradient paint stroke, delete; each applied (timed), shown (timed, to
/// the first frame with all of it uploaded), undone (not timed), several times.
pub(super) fn selection_edits(
    vp: &mut Viewport,
    doc: &mut app::editor::Document,
    size: (u32, u32),
    params: &render::SceneParams,
) -> Result<String> {
    use app::editor::command::Command;
    use app::selection::SelectOp;
    use app::selection_transform::SelectionTransform;
    use brickmap::objects::Axis;
    use glam::IVec3;
    let req = edit_request(params, size, 0.5);
    let (min, max) = (IVec3::new(64, 48, 64), IVec3::new(319, 111, 319));
    // The terrain's top voxel at (192, 192): the wand's and the extrude's start.
    let top = {
        let view = doc.scene.world.read();
        (0..view.dims().voxels().y)
            .rev()
            .map(|y| IVec3::new(192, y, 192))
            .find(|v| matches!(view.voxel(*v), Ok(Some(_))))
            .unwrap_or(IVec3::new(192, 0, 192))
    };
    // `undo`: the operation changes voxels, is shown, then undone for the next run.
    let select = Command::Select(SelectOp::Replace { min, max });
    let mut text = format!(
        "\nselection {min} … {max} (256 x 64 x 256), internal scale 0.5, {} runs each\noperation                 voxels changed   apply ms median (max)   edit → frame ms median (max), frames   uploaded MB\n",
        objects::REPEATS
    );
    let cases = [
        ("select", select.clone(), false),
        ("copy", Command::Copy, false),
        (
            "paste at (200,100,200)",
            Command::Paste {
                at: IVec3::new(200, 100, 200),
            },
            true,
        ),
        (
            "move by (1,0,1)",
            Command::MoveSelection(IVec3::new(1, 0, 1)),
            true,
        ),
        (
            "move by (8,0,8)",
            Command::MoveSelection(IVec3::new(8, 0, 8)),
            true,
        ),
        (
            "turn about y",
            Command::TransformSelection(SelectionTransform::Turn {
                axis: Axis::Y,
                quarters: 1,
            }),
            true,
        ),
        (
            "mirror x",
            Command::TransformSelection(SelectionTransform::Flip(Axis::X)),
            true,
        ),
        (
            "stamp x4 (turned)",
            Command::Stamp {
                at: (0..4).map(|k| IVec3::new(20 + 70 * k, 120, 100)).collect(),
                quarters: 1,
            },
            true,
        ),
        (
            "extrude top by 4",
            Command::Extrude {
                voxel: top,
                normal: IVec3::Y,
                distance: 4,
                same_material: false,
            },
            true,
        ),
        (
            "gradient stroke r16",
            Command::Stroke(app::editor::command::Stroke {
                mode: app::editor::command::BrushMode::Paint,
                shape: app::editor::command::BrushShape::Sphere,
                size: 16.0,
                material: 0,
                mirror: Default::default(),
                points: (0..12)
                    .map(|k| glam::DVec3::new(150.0 + 16.0 * k as f64, 77.0, 256.0))
                    .collect(),
                axis: Default::default(),
                in_selection: false,
                paint: app::editor::command::PaintMode::Gradient { to: 3 },
            }),
            true,
        ),
        (
            "wand (solid)",
            Command::Select(SelectOp::Wand {
                start: top,
                by_material: false,
                diagonal: false,
                how: app::wand::Combine::Replace,
            }),
            false,
        ),
        // The box again for the delete.
        ("select (again)", select.clone(), false),
        ("delete", Command::DeleteSelection, true),
    ];
    doc.execute(select)?;
    doc.execute(Command::Copy)?;
    frames_until_shown(vp, &doc.scene.world, &req)?;
    for (name, command, undo) in cases {
        let t = objects::timed(vp, doc, &req, &command, undo)?;
        let shown_text = if undo {
            format!(
                "{:.1} ({:.1}), {:.0}                 {:.2}",
                t.shown.0, t.shown.1, t.frames, t.mb
            )
        } else {
            "- (no voxel changes)".into()
        };
        text += &format!(
            "{name:<25} {:<16} {:.1} ({:.1})            {shown_text}\n",
            t.changed, t.apply.0, t.apply.1
        );
    }
    Ok(text)
}
