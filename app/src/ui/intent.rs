//! What the user asks for, as the editor's parts hand it on: key-map actions with the
//! modifier keys held and the selection's nudges, and the panels' events. Vocabulary only:
//! the key map, the input handlers, the panels and the tools all speak it, and it imports
//! none of them.

use super::purpose::Purpose;
use crate::editor::command::{BrushMode, BrushShape};
use brickmap::objects::Axis;
use render::{RenderSettings, Sky, Sun};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Modifier keys held.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Mods {
    /// Control (Command on macOS).
    pub ctrl: bool,
    /// Shift.
    pub shift: bool,
    /// Alt.
    pub alt: bool,
}

/// What a shortcut does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Action {
    /// Undo the latest step.
    Undo,
    /// Redo the latest undone step.
    Redo,
    /// New scene.
    New,
    /// Open a file.
    Open,
    /// Save (Save As when the document has no project file).
    Save,
    /// Save under a new name.
    SaveAs,
    /// Import a .vox into the scene.
    Import,
    /// Export as .vox.
    Export,
    /// Export a mesh (.glb, .gltf, .obj, .ply).
    ExportMesh,
    /// A new document: terrain from a heightmap image.
    NewFromHeightmap,
    /// Frame the scene's content.
    Frame,
    /// Switch between perspective and orthographic.
    ToggleProjection,
    /// Brush one voxel smaller.
    BrushSmaller,
    /// Brush one voxel larger.
    BrushLarger,
    /// Brush mode.
    Mode(BrushMode),
    /// Brush shape.
    Shape(BrushShape),
    /// Store the view in camera slot n (1..=9).
    StoreView(u8),
    /// Recall camera slot n.
    RecallView(u8),
    /// Drop the materials no voxel uses.
    RemoveUnusedMaterials,
    /// The selection tool.
    SelectTool,
    /// Show or hide the ground grid.
    ToggleGrid,
    /// The ruler (Measure tool).
    MeasureTool,
    /// The Extrude tool.
    ExtrudeTool,
    /// The Stamp tool (the clipboard as a brush).
    StampTool,
    /// Turn the stamp a quarter turn about the vertical.
    StampTurn,
    /// Turn it back.
    StampTurnBack,
    /// The brush's next colour mode (solid, gradient, random; in paint mode darken and
    /// brighten too).
    NextColourMode,
    /// The selection tool's next mode (box, the wands, the screen rectangles).
    NextSelectMode,
    /// Arrange mode (pick and move objects), or back to the brush.
    ArrangeTool,
    /// Select the whole grid.
    SelectAll,
    /// Select nothing.
    SelectNone,
    /// Scale the selection's voxels × 2 about its centre.
    DoubleSelection,
    /// Scale them × ½ (the majority of each 2 × 2 × 2).
    HalveSelection,
    /// Select what is not selected.
    InvertSelection,
    /// One voxel more on every side of the selection.
    GrowSelection,
    /// One voxel less.
    ShrinkSelection,
    /// Select every voxel of the current material.
    SelectMaterial,
    /// Empty the selected voxels.
    DeleteSelection,
    /// Fill the selection with the current material.
    FillSelection,
    /// Paint the selection's solid voxels with the current material.
    PaintSelection,
    /// Copy the selection's solid voxels.
    Copy,
    /// Copy, then delete.
    Cut,
    /// Place the copy: it follows the cursor until a click.
    Paste,
    /// Move the selection a voxel (Shift: a brick).
    Nudge(Nudge),
    /// Turn the picked objects (arrange mode) or the object brushes edit a quarter turn
    /// about an axis (counter-clockwise looking down it).
    Turn(Axis),
    /// The same, clockwise.
    TurnBack(Axis),
    /// Mirror them along an axis.
    Flip(Axis),
    /// Another object copying the model of the picked object (arrange mode) or the edited one.
    DuplicateObject,
    /// Another object placing the same model as the picked or edited one.
    InstanceObject,
    /// The picked or edited object gets its own copy of a shared model.
    MakeUnique,
    /// The picked nodes into a new group.
    GroupObjects,
    /// The picked group's children take its place.
    Ungroup,
    /// The picked objects into one new object.
    MergeObjects,
    /// The selected voxels of the edited object into a new object.
    SplitSelection,
    /// Show or hide the shortcut list.
    Help,
    /// Quit (asks about unsaved changes).
    Quit,
}

/// The key map the editor starts from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum KeyPreset {
    /// MagicaVoxel's shortcuts where it has them.
    #[default]
    MagicaVoxel,
    /// Blender's where an action matches one of its own: A / Alt + A select all / none, X and
    /// Delete delete, Shift + D duplicate, Alt + D instance, P separate the selection into an
    /// object, B the selection tool (Shift + B the sphere brush), Shift + X erase, Home and
    /// Numpad . frame; the rest as MagicaVoxel's.
    Blender,
}

/// A move of the selection by a key.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Nudge {
    /// Towards the screen's left.
    Left,
    /// Towards the screen's right.
    Right,
    /// Away from the camera (horizontally).
    Away,
    /// Towards the camera (horizontally).
    Towards,
    /// Up.
    Up,
    /// Down.
    Down,
}

/// What the user asked for through the panels.
#[derive(Clone, Debug)]
pub enum UiEvent {
    /// A shortcut's action (menus name the same actions).
    Action(Action),
    /// Another key map preset.
    KeyPreset(KeyPreset),
    /// Replace a material by the brush's in the selection or the edited object.
    ReplaceMaterial {
        /// The material replaced.
        from: u8,
    },
    /// Open a recent file.
    OpenRecent(PathBuf),
    /// The sun changed (one undo step per drag: commands coalesce).
    SetSun(Sun),
    /// The sky changed.
    SetSky(Sky),
    /// Scene render settings changed (bounces).
    SetSettings(RenderSettings),
    /// Import a .vox at an offset (undoable).
    Import {
        /// The file.
        path: PathBuf,
        /// Added to its voxels after the shift into the grid.
        offset: [i32; 3],
    },
    /// Make the current view the scene's camera (undoable).
    UseViewAsSceneCamera,
    /// A colour of the table changed (one step per drag).
    SetColour {
        /// Colour index.
        index: u8,
        /// sRGB.
        rgb: [u8; 3],
    },
    /// A material changed.
    SetMaterial {
        /// Its index.
        index: u8,
        /// The new value.
        material: crate::editor::command::MaterialSpec,
    },
    /// Load (false: ask for a .png or .vox) or save (true: as a PNG strip) the palette.
    PaletteFile {
        /// Save rather than load.
        save: bool,
    },
    /// A material was added.
    AddMaterial(crate::editor::command::MaterialSpec),
    /// A parameter-table value changed (roughness, IOR, strength).
    SetParam {
        /// Which table.
        kind: crate::editor::command::KindSpec,
        /// Slot 0..64.
        index: u8,
        /// The value.
        value: f32,
    },
    /// An object command (the Objects window).
    Objects(crate::editor::objects::ObjectCommand),
    /// A new empty object of this size, under the view's pivot.
    NewObject(glam::IVec3),
    /// Edit this object's voxels: it becomes the one brushes edit, arrange mode ends.
    EditObject(brickmap::objects::NodeId),
    /// Ask where to write a finished render (File → Render image…), then render.
    RenderImage,
    /// Replace the scene's voxels by generated terrain (undoable).
    Generate(crate::editor::command::TerrainSpec),
    /// Go back (undo) or forward (redo) this many steps in the history.
    Jump {
        /// Steps to undo.
        undo: usize,
        /// Steps to redo.
        redo: usize,
    },
    /// The unsaved-changes question was answered.
    Unsaved(UnsavedAnswer),
    /// The in-app file browser confirmed a path for this purpose.
    Picked(Purpose, PathBuf),
    /// The in-app file browser was closed without a choice.
    PickCancelled,
    /// The recovery offer was answered (true: recover).
    Recover(bool),
    /// New scene of this size in voxels, terrain or empty.
    NewScene {
        /// Voxels per axis.
        size: (u32, u32, u32),
        /// Generate noise terrain.
        terrain: bool,
    },
}

/// Answers to "save changes?".
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UnsavedAnswer {
    /// Save first, then go on.
    Save,
    /// Go on without saving.
    Discard,
    /// Stay.
    Cancel,
}
