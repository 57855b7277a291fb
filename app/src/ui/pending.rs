//! What the editor waits on before the document changes hands: an answer to the unsaved-
//! changes question, a save that must finish before an open, a new scene or a quit goes on,
//! a built scene on its way (which a file opened meanwhile wins over), a recovery file being
//! loaded. `document.rs` and `actions.rs` ask it; nothing else touches it.

use std::path::PathBuf;

/// What to do once the unsaved-changes question is answered (or the save it asked for is
/// done).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Pending {
    Quit,
    Open(Option<PathBuf>),
    /// A new document from a heightmap image (asked for next).
    Heightmap,
    New {
        size: (u32, u32, u32),
        terrain: bool,
    },
}

/// The waits.
#[derive(Debug, Default)]
pub(super) struct Waits {
    /// Asked about unsaved changes; this runs after the answer.
    unsaved: Option<Pending>,
    /// Runs once the save the answer asked for is written.
    after_save: Option<Pending>,
    /// A built scene (the default one, or New) is on its way: a loaded scene without a path
    /// replaces the document only then.
    built_scene: bool,
    /// The file being loaded is the recovery file (the document it makes is unsaved work,
    /// not that file).
    recovery: bool,
}

impl Waits {
    /// The question about unsaved changes is asked; `then` waits for the answer.
    pub(super) fn ask(&mut self, then: Pending) {
        self.unsaved = Some(then);
    }

    /// The question was answered: what was waiting on it.
    pub(super) fn answered(&mut self) -> Option<Pending> {
        self.unsaved.take()
    }

    /// `then` runs once the save now started is written.
    pub(super) fn after_save(&mut self, then: Pending) {
        self.after_save = Some(then);
    }

    /// A save was written: what waited on it.
    pub(super) fn saved(&mut self) -> Option<Pending> {
        self.after_save.take()
    }

    /// The save failed, or its file was never picked: what waited on it is dropped.
    pub(super) fn save_abandoned(&mut self) {
        self.after_save = None;
    }

    /// A scene is being built (the default scene, New).
    pub(super) fn building(&mut self) {
        self.built_scene = true;
    }

    /// The recovery file is being loaded (instead of a built scene).
    pub(super) fn recovering(&mut self) {
        self.built_scene = false;
        self.recovery = true;
    }

    /// A scene arrived, from a file (`from_file`) or built. None: it is a built scene nobody
    /// waits for any more (a file opened meanwhile won), drop it. Some(recovered): it replaces
    /// the document; `recovered` says it came from the recovery file.
    pub(super) fn arrived(&mut self, from_file: bool) -> Option<bool> {
        if !from_file && !self.built_scene {
            return None;
        }
        self.built_scene = false;
        Some(std::mem::take(&mut self.recovery))
    }

    /// A load or a build failed: nothing waits for a built scene.
    pub(super) fn load_failed(&mut self) {
        self.built_scene = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_opened_while_the_default_scene_builds_wins() {
        let mut w = Waits::default();
        w.building();
        assert_eq!(w.arrived(true), Some(false));
        // The built scene arriving afterwards is dropped.
        assert_eq!(w.arrived(false), None);
        // One waited for is taken.
        w.building();
        assert_eq!(w.arrived(false), Some(false));
        assert_eq!(w.arrived(false), None);
    }

    #[test]
    fn the_recovery_file_replaces_a_built_scene_and_says_so_once() {
        let mut w = Waits::default();
        w.building();
        w.recovering();
        assert_eq!(w.arrived(false), None);
        assert_eq!(w.arrived(true), Some(true));
        assert_eq!(w.arrived(true), Some(false));
        w.building();
        w.load_failed();
        assert_eq!(w.arrived(false), None);
    }

    #[test]
    fn answers_and_saves_release_what_waits_once() {
        let mut w = Waits::default();
        w.ask(Pending::Quit);
        assert_eq!(w.answered(), Some(Pending::Quit));
        assert_eq!(w.answered(), None);
        w.after_save(Pending::Open(None));
        assert_eq!(w.saved(), Some(Pending::Open(None)));
        assert_eq!(w.saved(), None);
        w.after_save(Pending::Quit);
        w.save_abandoned();
        assert_eq!(w.saved(), None);
    }
}
