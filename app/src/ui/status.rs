//! The status line: the mode (the object brushes edit, or arrange mode and what is picked),
//! the voxel and face under the cursor, the selection's size, the ruler's measure, then the
//! renderer's figures.

use super::Editor;
use super::tools::Tool;

impl Editor {
    /// The status line, ending with `figures` (samples, GPU time, device…); `hovered` is
    /// the voxel and face under the cursor ([`Editor::hovered`], cast once per frame).
    pub(super) fn status_line(
        &self,
        figures: &str,
        hovered: Option<(glam::IVec3, glam::IVec3)>,
    ) -> String {
        let tool = self.settings.brush.tool;
        let mut parts = Vec::new();
        let doc = self.read();
        parts.push(if tool == Tool::Arrange {
            format!(
                "arrange ({} picked; Tab: edit)",
                self.panels.outliner.picked.len()
            )
        } else {
            let objects = doc.scene.objects();
            doc.scene
                .active()
                .and_then(|n| objects.tree().node(n).ok())
                .map_or_else(
                    || "no object to edit (Tab: arrange)".to_string(),
                    |n| format!("editing {} (Tab: arrange)", n.name),
                )
        });
        drop(doc);
        if let Some((voxel, normal)) = hovered {
            parts.push(super::measure::hover_text(voxel, normal));
        }
        if let Some((lo, hi)) = self
            .read()
            .scene
            .selection
            .as_ref()
            .and_then(|s| s.voxels.bounds())
        {
            parts.push(format!(
                "selection {}",
                super::preview::box_size_text(lo, hi)
            ));
        }
        if tool == Tool::Measure {
            parts.push(
                match self.controls.pointer.ruler.ends(hovered.map(|(v, _)| v)) {
                    Some((a, b)) => super::measure::text(a, b),
                    None => "measure: click a voxel, then another".into(),
                },
            );
        }
        parts.push(figures.to_string());
        parts.join(" · ")
    }
}
