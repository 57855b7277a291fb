//! `voxbrick stats` and `info`: a world's size, memory by GPU buffer, a pick ray and the
//! content hash.

use super::{emit, with_progress};
use anyhow::Result;
use app::builtin::{SceneSize, default_scene};
use brickmap::{Ray, World};
use glam::DVec3;
use std::time::Instant;

/// `voxbrick stats`: builds the built-in default scene and prints its statistics.
#[derive(clap::Args)]
pub(crate) struct StatsArgs {
    /// Scene size.
    #[arg(long, value_enum, default_value = "full")]
    size: SceneSize,
}

/// Builds the scene, timed, and prints [`stats_text`].
pub(crate) fn stats(a: StatsArgs, workers: usize) -> Result<()> {
    let started = Instant::now();
    let scene = with_progress("building the default scene".into(), || {
        default_scene(a.size, workers)
    })?;
    print_stats(&scene.world, started.elapsed().as_secs_f64())
}

fn print_stats(world: &World, seconds: f64) -> Result<()> {
    emit(&stats_text(world, seconds))
}

pub(crate) fn stats_text(world: &World, seconds: f64) -> String {
    let view = world.read();
    let dims = world.dims();
    let m = view.memory();
    let solid = view.solid_count();
    let v = dims.voxels();
    let b = dims.bricks();
    let table = view.materials();
    let mut kinds = [0usize; 4];
    for i in 0..table.len() {
        if let Ok(mat) = table.get(i as u8) {
            kinds[mat.kind as usize] += 1;
        }
    }
    let mut lines = vec![
        format!(
            "scene        {} x {} x {} voxels ({} x {} x {} bricks)",
            v.x, v.y, v.z, b.x, b.y, b.z
        ),
        format!(
            "built in     {:.1} ms on {} workers",
            seconds * 1e3,
            world.workers()
        ),
        format!("solid        {solid} voxels"),
        format!(
            "cells        {} stored bricks ({} uniform), {} full cells",
            view.brick_count(),
            m.uniform_bricks,
            m.full_cells
        ),
        format!(
            "materials    {} in the table ({} lambertian, {} metal, {} dielectric, {} emissive)",
            table.len(),
            kinds[0],
            kinds[1],
            kinds[2],
            kinds[3]
        ),
        format!(
            "lights       {} emissive faces sampled as lights",
            view.lights().len()
        ),
        format!(
            "gpu memory   {} bytes used, {} reserved",
            m.gpu_used(),
            m.gpu_reserved()
        ),
        format!("  brick index  {}", m.brick_index),
        format!("  bricks       {}", m.bricks_used),
        format!("  coarse grid  {}", m.coarse),
        format!(
            "  material     {} ({} payload)",
            m.material_used, m.material_payload
        ),
        format!("  tables       {}", m.tables),
        format!("  lights       {}", m.lights),
    ];
    if solid > 0 {
        lines.push(format!(
            "per voxel    {:.4} bytes per solid voxel",
            m.gpu_used() as f64 / solid as f64
        ));
    }
    // A pick ray straight down through the middle, as a brush would cast it.
    let centre = v.as_dvec3() * 0.5;
    let ray = Ray {
        origin: DVec3::new(centre.x + 0.5, v.y as f64 + 10.0, centre.z + 0.5),
        dir: -DVec3::Y,
    };
    lines.push(match view.ray_cast(&ray, f64::INFINITY) {
        Ok(Some((hit, material))) => {
            format!(
                "pick         voxel {} material {material} normal {} at t = {:.3}",
                hit.voxel, hit.normal, hit.t
            )
        }
        Ok(None) => "pick         nothing below the centre".to_string(),
        Err(e) => format!("pick         failed: {e}"),
    });
    lines.push(format!("content hash {:016x}", view.content_hash()));
    lines.join("\n") + "\n"
}
