//! `voxbrick`: the voxel scene editor's command line. For now it builds the built-in scene
//! and reports on it; the editor, file formats and renderer arrive with their issues.

mod scene;

use anyhow::Result;
use brickmap::{Ray, World};
use clap::{Parser, Subcommand};
use glam::DVec3;
use scene::SceneSize;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "voxbrick",
    version,
    about = "Voxel scene editor with a path-traced viewport"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Build the built-in default scene and print its statistics.
    Stats {
        /// Scene size.
        #[arg(long, value_enum, default_value = "full")]
        size: SceneSize,
        /// Worker threads (0: one per core).
        #[arg(long, default_value_t = 0)]
        workers: usize,
    },
}

fn main() -> std::process::ExitCode {
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("voxbrick: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Stats { size, workers } => stats(size, workers),
    }
}

fn stats(size: SceneSize, workers: usize) -> Result<()> {
    let started = Instant::now();
    let world = scene::default_scene(size, workers)?;
    let built = started.elapsed();
    print_stats(&world, built.as_secs_f64());
    Ok(())
}

fn print_stats(world: &World, build_seconds: f64) {
    let view = world.read();
    let dims = world.dims();
    let m = view.memory();
    let solid = view.solid_count();
    let v = dims.voxels();
    println!(
        "scene        {} x {} x {} voxels ({} x {} x {} bricks)",
        v.x,
        v.y,
        v.z,
        dims.bricks().x,
        dims.bricks().y,
        dims.bricks().z
    );
    println!(
        "built in     {:.1} ms on {} workers",
        build_seconds * 1e3,
        world.workers()
    );
    println!("solid        {solid} voxels");
    println!(
        "cells        {} stored bricks ({} uniform), {} full cells",
        view.brick_count(),
        m.uniform_bricks,
        m.full_cells
    );
    println!("materials    {} in the table", view.materials().len());
    println!(
        "gpu memory   {} bytes used, {} reserved",
        m.gpu_used(),
        m.gpu_reserved()
    );
    println!("  brick index  {}", m.brick_index);
    println!("  bricks       {}", m.bricks_used);
    println!("  coarse grid  {}", m.coarse);
    println!(
        "  material     {} ({} payload)",
        m.material_used, m.material_payload
    );
    println!("  tables       {}", m.tables);
    if solid > 0 {
        println!(
            "per voxel    {:.4} bytes per solid voxel",
            m.gpu_used() as f64 / solid as f64
        );
    }
    // A pick ray straight down through the middle, as a brush would cast it.
    let centre = v.as_dvec3() * 0.5;
    let ray = Ray {
        origin: DVec3::new(centre.x + 0.5, v.y as f64 + 10.0, centre.z + 0.5),
        dir: -DVec3::Y,
    };
    match view.ray_cast(&ray, f64::INFINITY) {
        Ok(Some((hit, material))) => {
            println!(
                "pick         voxel {} material {material} normal {} at t = {:.3}",
                hit.voxel, hit.normal, hit.t
            )
        }
        Ok(None) => println!("pick         nothing below the centre"),
        Err(e) => println!("pick         failed: {e}"),
    }
    println!("content hash {:016x}", view.content_hash());
}
