//! `voxbrick new`, `convert` and `info`: scene files created, converted and described.

use super::stats::stats_text;
use super::{args, emit, with_progress};
use anyhow::{Context, Result, bail};
use app::Scene;
use app::builtin::{terrain_materials, thesis_scene, thesis_terrain};
use app::formats::{self, Format};
use brickmap::terrain::{NoiseKind, NoiseTerrain};
use brickmap::{GridDims, World, WorldConfig};
use glam::IVec3;
use render::SceneParams;
use std::path::PathBuf;
use std::time::Instant;

/// `voxbrick new`: a noise terrain or the thesis scene, written to a file.
#[derive(clap::Args)]
pub(crate) struct NewArgs {
    /// A noise terrain with water (the parameters below).
    #[arg(long, conflicts_with = "thesis")]
    terrain: bool,
    /// The thesis benchmark scene: 512×256×512 terrain, water and a metal statue.
    #[arg(long)]
    thesis: bool,
    /// Terrain from a heightmap image (PNG, 8 or 16 bits; a pixel a column, white
    /// --height-max voxels tall, default 256).
    #[arg(long, conflicts_with_all = ["thesis", "terrain"])]
    heightmap: Option<PathBuf>,
    /// Grid size in voxels, as WxHxD (multiples of 8 are used as they are).
    #[arg(long, value_parser = args::grid_size, default_value = "512x256x512")]
    size: IVec3,
    /// Noise seed.
    #[arg(long, default_value_t = 2022)]
    seed: u32,
    /// Noise function: perlin, open-simplex, super-simplex or value.
    #[arg(long, value_parser = args::noise, default_value = "perlin")]
    noise: NoiseKind,
    /// Wavelength of the first octave, in voxels.
    #[arg(long)]
    scale: Option<f64>,
    /// Octaves of fractal noise (1..=12).
    #[arg(long, default_value_t = 5)]
    octaves: u32,
    /// Lowest surface height in voxels.
    #[arg(long)]
    height_min: Option<u32>,
    /// Highest surface height in voxels.
    #[arg(long)]
    height_max: Option<u32>,
    /// Water level in voxels (0: none).
    #[arg(long)]
    water_level: Option<u32>,
    /// Output file (.ron or .vox).
    output: PathBuf,
}

/// Generates the scene and writes it atomically.
pub(crate) fn new(a: NewArgs, workers: usize) -> Result<()> {
    if !a.terrain && !a.thesis && a.heightmap.is_none() {
        bail!(
            "say what to create: --terrain (with its parameters), --heightmap FILE.png or --thesis"
        );
    }
    Format::of(&a.output)?;
    let started = Instant::now();
    let scene = with_progress("generating".into(), || {
        if a.thesis {
            return thesis_scene(workers);
        }
        if let Some(image) = &a.heightmap {
            let height = a.height_max.unwrap_or(256);
            return Ok(app::builtin::heightmap_scene(image, height, workers)?);
        }
        let dims = GridDims::from_voxels(a.size.as_uvec3()).context("grid size")?;
        let world = World::new(dims, WorldConfig::with_workers(workers))?;
        let h = dims.voxels().y as u32;
        let mut params = thesis_terrain(terrain_materials(&world)?, h);
        params.seed = a.seed;
        params.noise = a.noise;
        params.octaves = a.octaves;
        params.scale = a.scale.unwrap_or(params.scale);
        params.height_range = (
            a.height_min.unwrap_or(params.height_range.0),
            a.height_max.unwrap_or(params.height_range.1),
        );
        params.water_level = a.water_level.unwrap_or(params.water_level);
        world.apply_unrecorded(NoiseTerrain::new(params, dims)?.edit())?;
        world.take_dirty();
        Ok(Scene::new(
            world,
            SceneParams::framing(dims.voxels().as_dvec3()),
        ))
    })?;
    let generated = started.elapsed().as_secs_f64();
    // How the bulk work ran: a generator that stops using every worker, or per-voxel work
    // on the path, shows here (and fails the CLI test).
    let work = brickmap::census::read();
    save(&scene, &a.output)?;
    eprintln!(
        "generated in {generated:.2} s on {} workers (adopted as one object on {} threads; \
         {} bricks rewritten voxel by voxel, {} composited, {} undo records), wrote {} in \
         {:.2} s total",
        scene.world.workers(),
        work.adopted_on,
        work.voxel_bricks,
        work.composited,
        work.undo_records,
        a.output.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Writes `scene` to `path` (atomically, as every save), with a spinner.
fn save(scene: &Scene, path: &std::path::Path) -> Result<()> {
    with_progress(format!("writing {}", path.display()), || {
        Ok(app::formats::save(scene, path)?)
    })
}

/// `voxbrick convert`: between project (.ron), MagicaVoxel (.vox), Qubicle (.qb) and Sponge
/// schematic (.schem) files, or to a mesh (.obj, .glb, .gltf, .ply).
#[derive(clap::Args)]
pub(crate) struct ConvertArgs {
    /// Input file (.ron, .vox, .qb or .schem).
    input: PathBuf,
    /// Output file (.ron, .vox, .qb, .schem, or a mesh: .obj with .mtl and a palette PNG
    /// beside it, .glb, .gltf, .ply); replaced atomically.
    output: PathBuf,
    /// .schem: the block table (RON, as assets/schem/blocks.ron) instead of the built-in one.
    #[arg(long, value_name = "FILE.ron")]
    blocks: Option<PathBuf>,
    /// Mesh: one quad per voxel face (watertight) instead of merged rectangles (which meet
    /// at T-junctions).
    #[arg(long)]
    faces: bool,
    /// Mesh: one part per object (named; glTF nodes under their groups), transforms applied;
    /// else the scene as shown, one mesh.
    #[arg(long)]
    per_object: bool,
    /// Mesh, glTF, with --per-object: each object's placement kept as its node's matrix
    /// (its mesh in its own frame) instead of applied.
    #[arg(long)]
    keep_transforms: bool,
    /// Mesh: units per voxel (glTF reads metres).
    #[arg(long, default_value_t = 1.0)]
    voxel_size: f64,
    /// Offset added to imported .vox voxels, as X,Y,Z (the file is then flattened into one
    /// object; without it and --include-hidden, its objects are kept).
    #[arg(long, value_parser = args::ivec3, default_value = "0,0,0")]
    offset: IVec3,
    /// Import hidden nodes and layers too, shown (the file is flattened into one object).
    #[arg(long)]
    include_hidden: bool,
    /// Write one object: what the input's visible objects show, as one grid.
    #[arg(long)]
    flatten: bool,
}

/// Reads the input (reporting what a .vox import dropped) and writes the output.
pub(crate) fn convert(a: ConvertArgs, workers: usize) -> Result<()> {
    let started = Instant::now();
    let blocks = match &a.blocks {
        Some(p) => formats::schem::BlockTable::load(p)?,
        None => formats::schem::BlockTable::builtin(),
    };
    let scene = with_progress(
        format!("reading {}", a.input.display()),
        || match Format::of(&a.input)? {
            Format::Project => {
                let scene = formats::project::load(&a.input, workers)?;
                Ok(if a.flatten { scene.flattened() } else { scene })
            }
            Format::Vox => {
                let options = formats::vox::ImportOptions {
                    offset: a.offset,
                    include_hidden: a.include_hidden,
                };
                // Flattened where asked to (an offset, hidden nodes shown); else its objects.
                let (scene, report) = if a.flatten || a.include_hidden || a.offset != IVec3::ZERO {
                    formats::vox::import_file(&a.input, &options, workers)?
                } else {
                    let bytes = std::fs::read(&a.input)
                        .with_context(|| format!("reading {}", a.input.display()))?;
                    let import = formats::vox::import_objects(&bytes, &a.input, workers)?;
                    (import.scene, import.report)
                };
                eprintln!(
                    "imported {} voxels from {} instances of {} models, {} materials",
                    report.voxels, report.instances, report.models, report.materials
                );
                for line in &report.dropped {
                    eprintln!("  dropped: {line}");
                }
                Ok(scene)
            }
            Format::Qb => {
                let bytes = std::fs::read(&a.input)
                    .with_context(|| format!("reading {}", a.input.display()))?;
                let (scene, r) = formats::qb::import(&bytes, &a.input, workers)?;
                eprintln!(
                    "imported {} voxels from {} matrices, {} colours",
                    r.voxels, r.matrices, r.colours
                );
                if r.merged_colours > 0 {
                    eprintln!(
                        "  merged: {} colours beyond 256 into their nearest",
                        r.merged_colours
                    );
                }
                Ok(if a.flatten { scene.flattened() } else { scene })
            }
            Format::Schem => {
                let bytes = std::fs::read(&a.input)
                    .with_context(|| format!("reading {}", a.input.display()))?;
                let (scene, r) = formats::schem::import(&bytes, &a.input, &blocks, workers)?;
                eprintln!(
                    "imported {} voxels of a {}x{}x{} version {} schematic",
                    r.voxels, r.size.x, r.size.y, r.size.z, r.version
                );
                if !r.derived.is_empty() {
                    eprintln!(
                        "  {} block ids shown as the listed block their name derives from (e.g. {})",
                        r.derived.len(),
                        r.derived
                            .iter()
                            .take(3)
                            .map(|(a, b)| format!("{a} as {b}"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    );
                }
                for (name, n) in &r.unknown {
                    eprintln!(
                        "  not in the block table (shown as its unknown material): {name} ({n} blocks)"
                    );
                }
                if r.block_entities + r.entities > 0 || r.biomes {
                    eprintln!(
                        "  dropped: {} block entities, {} entities{}",
                        r.block_entities,
                        r.entities,
                        if r.biomes { ", biomes" } else { "" }
                    );
                }
                Ok(scene)
            }
        },
    )?;
    if app::formats::mesh::MeshFormat::of(&a.output).is_some() {
        let options = app::formats::mesh::MeshOptions {
            greedy: !a.faces,
            per_object: a.per_object,
            voxel_size: a.voxel_size,
            keep_transforms: a.keep_transforms,
        };
        // A bar with the part done and the time left (Ctrl + C stops: nothing is written).
        let bar = indicatif::ProgressBar::new(1000);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg} {bar:40} {percent:>3}% {elapsed} (about {eta} left)",
            )
            .expect("valid template"),
        );
        bar.set_message(format!("writing {}", a.output.display()));
        let stats = app::formats::mesh::export_watched(&scene, &a.output, &options, &|f| {
            bar.set_position((f * 1000.0) as u64);
            true
        });
        bar.finish_and_clear();
        let stats = stats?;
        eprintln!(
            "{} parts, {} quads, {} triangles",
            stats.parts, stats.quads, stats.triangles
        );
    } else if Format::of(&a.output)? == Format::Schem {
        let r = with_progress(format!("writing {}", a.output.display()), || {
            Ok(formats::schem::export(&scene, &a.output, &blocks)?)
        })?;
        if r.as_nearest > 0 {
            eprintln!(
                "  {} materials written as the nearest block of the table",
                r.as_nearest
            );
        }
    } else if Format::of(&a.output)? == Format::Qb {
        let r = with_progress(format!("writing {}", a.output.display()), || {
            Ok(formats::qb::export(&scene, &a.output)?)
        })?;
        if r.as_colour + r.hidden > 0 {
            eprintln!(
                "  {} non-lambertian materials written as their colour, {} hidden objects left out",
                r.as_colour, r.hidden
            );
        }
    } else {
        save(&scene, &a.output)?;
    }
    eprintln!(
        "wrote {} in {:.2} s",
        a.output.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `voxbrick info`: a scene file's dimensions, voxel count, materials, memory and view.
#[derive(clap::Args)]
pub(crate) struct InfoArgs {
    /// A .ron, .vox, .qb or .schem file.
    file: PathBuf,
    /// Print every node of the object tree (else the first 200).
    #[arg(long)]
    tree: bool,
}

/// The nodes `voxbrick info` lists without `--tree`.
const TREE_LINES: usize = 200;

/// The object tree, a line per node (`Objects::outline`): each object's model with its
/// size, voxels and how many objects place it; at most `limit` lines, then how many more.
fn tree_text(o: &brickmap::objects::Objects, limit: usize) -> String {
    let tree = o.tree();
    let lines = o.outline(true, |id, m| {
        let s = m.size();
        let users = tree.instances(id).len();
        let shared = if users > 1 {
            format!(", placed by {users}")
        } else {
            String::new()
        };
        format!(
            "model {} {}x{}x{}, {} voxels{shared}",
            id.0,
            s.x,
            s.y,
            s.z,
            m.solid_count()
        )
    });
    let mut text = String::from("tree\n");
    for l in lines.iter().take(limit) {
        text += &format!("  {l}\n");
    }
    if lines.len() > limit {
        text += &format!(
            "  … {} more nodes (--tree lists them all)\n",
            lines.len() - limit
        );
    }
    text
}

/// One line on a scene's objects: how many, the models they place and how many of them
/// are shared, groups, hidden ones, layers.
fn objects_text(o: &brickmap::objects::Objects) -> String {
    use brickmap::objects::{NodeKind, ObjectTree};
    let tree = o.tree();
    let (mut objects, mut groups, mut hidden) = (0, 0, 0);
    for id in tree.subtree(ObjectTree::ROOT).unwrap_or_default() {
        let Ok(n) = tree.node(id) else { continue };
        match n.kind {
            NodeKind::Object { .. } => objects += 1,
            NodeKind::Group { .. } if id != ObjectTree::ROOT => groups += 1,
            NodeKind::Group { .. } => {}
        }
        hidden += usize::from(!n.visible);
    }
    let placed: Vec<usize> = o
        .models()
        .keys()
        .map(|m| tree.instances(*m).len())
        .filter(|n| *n > 0)
        .collect();
    let shared = placed.iter().filter(|n| **n > 1).count();
    let layers = tree.layers();
    format!(
        "objects      {objects} objects of {} models ({shared} shared), {groups} groups, {hidden} hidden; {} layers ({} hidden)\n",
        placed.len(),
        layers.len(),
        layers.iter().filter(|l| !l.visible).count()
    )
}

/// Prints the file's statistics, objects, camera and render settings.
pub(crate) fn info(a: InfoArgs, workers: usize) -> Result<()> {
    let file = a.file;
    let started = Instant::now();
    let scene = with_progress(format!("reading {}", file.display()), || {
        Ok(app::formats::load(&file, workers)?)
    })?;
    let loaded = started.elapsed().as_secs_f64();
    let work = brickmap::census::read();
    let p = &scene.params;
    let mut text = format!("file         {}\n", file.display());
    text += &format!(
        "loaded       in {loaded:.2} s on {} workers (adopted as one object on {} threads; {} bricks rewritten voxel by voxel, {} composited, {} undo records)\n",
        scene.world.workers(),
        work.adopted_on,
        work.voxel_bricks,
        work.composited,
        work.undo_records
    );
    text += &stats_text(&scene.world, started.elapsed().as_secs_f64());
    text += &objects_text(&scene.objects());
    text += &tree_text(
        &scene.objects(),
        if a.tree { usize::MAX } else { TREE_LINES },
    );
    let lens = match p.camera.projection {
        render::Projection::Perspective => format!("fov {:.1}", p.camera.fov_y_deg),
        render::Projection::Orthographic { height } => {
            format!("orthographic {height:.1} voxels tall")
        }
    };
    text += &format!(
        "camera       at {} yaw {:.1} pitch {:.1} {lens}\nrender       {} spp, {} bounces, {}x{}\n",
        p.camera.position,
        p.camera.yaw_deg,
        p.camera.pitch_deg,
        p.settings.samples_per_pixel,
        p.settings.max_bounces,
        p.settings.internal_resolution.0,
        p.settings.internal_resolution.1
    );
    emit(&text)
}
