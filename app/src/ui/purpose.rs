//! What a file dialog is for: its title, the files it shows, whether it writes. The native
//! dialogs (`files.rs`, `dialog_tools.rs`) and the in-app browser (`browser.rs`) share it.

/// Why a file was asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// Replace the document.
    Open,
    /// Write the project here and make it the document's file.
    SaveAs,
    /// Add a .vox to the scene (undoable command).
    Import,
    /// Write a .vox.
    Export,
    /// Write a mesh (.glb, .gltf, .obj, .ply).
    ExportMesh,
    /// Read a heightmap image into a new terrain.
    Heightmap,
    /// Read a palette (.png strip or .vox).
    LoadPalette,
    /// Write the palette as a PNG strip.
    SavePalette,
    /// Write a finished render (File → Render image…).
    RenderImage,
}

impl Purpose {
    /// The extensions this purpose's files have, and their description.
    pub fn filter(self) -> (&'static str, &'static [&'static str]) {
        match self {
            Purpose::Open => ("Scenes", &["ron", "vox", "qb", "schem"]),
            Purpose::SaveAs => ("voxbrick project", &["ron"]),
            Purpose::Import => ("MagicaVoxel", &["vox"]),
            Purpose::Export => ("Voxel formats", &["vox", "qb", "schem"]),
            Purpose::ExportMesh => ("Mesh", &["glb", "gltf", "obj", "ply"]),
            Purpose::Heightmap => ("Heightmap (PNG, 8 or 16 bit)", &["png"]),
            Purpose::LoadPalette => ("Palette", &["png", "vox"]),
            Purpose::SavePalette => ("PNG palette strip", &["png"]),
            Purpose::RenderImage => ("Picture", &["png", "exr", "pfm"]),
        }
    }

    /// Whether the purpose writes a file (the name may be new; an existing one is replaced).
    pub fn saves(self) -> bool {
        matches!(
            self,
            Purpose::SaveAs
                | Purpose::Export
                | Purpose::ExportMesh
                | Purpose::SavePalette
                | Purpose::RenderImage
        )
    }

    /// The dialog's title.
    pub fn title(self) -> &'static str {
        match self {
            Purpose::Open => "Open a scene",
            Purpose::SaveAs => "Save the scene as",
            Purpose::Import => "Import a .vox",
            Purpose::Export => "Export as .vox, .qb or .schem",
            Purpose::ExportMesh => "Export a mesh",
            Purpose::Heightmap => "A new terrain from a heightmap",
            Purpose::LoadPalette => "Load a palette",
            Purpose::SavePalette => "Save the palette as",
            Purpose::RenderImage => "Render the image to",
        }
    }
}
