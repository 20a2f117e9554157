//! `aprt simulate`: the ground-truth transfer of every frame, at the vertices or, with
//! `--surface N`, at points spread over the surface ([`crate::surface`]) through a checkpoint
//! that a bake farm's shards may share.

use anyhow::{Context, Result, bail};

use crate::bake::checkpoint::{Checkpoint, OnExisting};
use crate::cli::args::SimulateArgs;
use crate::cli::source::PosedMeshes;
use crate::cli::terminal::Terminal;
use crate::cli::{checkpoint_output, on_existing, shard_done, write_npy};
use crate::io::outputs::{Output, check};
use crate::progress::Reporter;
use crate::surface::{SurfacePoints, SurfaceTarget};

/// Columns of the `--points` file: triangle, three barycentric coordinates, area weight.
const POINT_COLUMNS: usize = 5;

/// Triangle indices float32 holds exactly (2^24), the bound of `--points`' first column.
const EXACT_F32_INDICES: usize = 1 << 24;

/// Runs `aprt simulate`.
pub fn run(args: &SimulateArgs) -> Result<()> {
    match args.surface {
        None => at_vertices(args),
        Some(count) => at_surface(args, count),
    }
}

/// The per-vertex bake: every pose in one piece, no checkpoint, so the flags that steer one
/// apply to `--surface` alone.
fn at_vertices(args: &SimulateArgs) -> Result<()> {
    let surface_only = [
        ("--points", args.points.is_some()),
        ("--checkpoint", args.checkpoint.is_some()),
        ("--resume", args.resume),
        ("--shard", args.shard.is_some()),
    ];
    if let Some((flag, _)) = surface_only.iter().find(|(_, given)| *given) {
        bail!(
            "{flag} applies to --surface only (the per-vertex bake runs in one piece): give --surface N, or leave {flag} out"
        );
    }
    check(&[Output::file(&args.npy, "--npy")], &args.source.inputs())?;
    let settings = args.bake.settings();
    let meshes = args.source.meshes(&settings, None, &Terminal)?.poses;
    let transfer = crate::bake::bake_poses(&meshes, &settings, &Terminal)?;
    let n2 = settings.order * settings.order;
    write_npy(
        &args.npy,
        &[meshes.len(), meshes[0].vertex_count(), n2],
        &transfer.concat(),
    )
}

/// `--surface count`: `count` points spread by area over the bind mesh, baked on every pose
/// through the checkpoint (a shard bakes its share and stops); the final run writes the
/// transfer, and with `--points` the points, then removes the checkpoint.
fn at_surface(args: &SimulateArgs, count: usize) -> Result<()> {
    let (checkpoint, mut inputs) =
        checkpoint_output(args.checkpoint.as_deref(), &args.npy, "--npy");
    inputs.extend(args.source.inputs());
    let mut outputs = vec![Output::file(&args.npy, "--npy"), checkpoint.clone()];
    if let Some(points) = &args.points {
        outputs.push(Output::file(points, "--points"));
    }
    check(&outputs, &inputs)?;
    let settings = args.bake.settings();
    let PosedMeshes { bind, poses } = args.source.meshes(&settings, Some(count), &Terminal)?;
    if let Some(path) = &args.points
        && bind.triangles.len() > EXACT_F32_INDICES
    {
        bail!(
            "--points {}: the mesh has {} triangles, more than the {EXACT_F32_INDICES} whose indices float32 holds exactly",
            path.display(),
            bind.triangles.len()
        );
    }
    let points = SurfacePoints::spread(&bind, count)
        .with_context(|| format!("--surface {count}: spreading points over the bind mesh"))?;
    let target = SurfaceTarget(&points);
    let frame = |f: usize| format!("frame {f}");
    let dir = &checkpoint.path;
    if let Some(shard) = args.shard {
        let mut store = Checkpoint::open_at(dir, OnExisting::Resume, &settings, &poses, &target)?;
        let baked = store.bake_shard(&poses, &target, shard, frame, &Terminal)?;
        shard_done(&baked, "aprt simulate --surface");
        return Ok(());
    }
    let mut store = Checkpoint::open_at(dir, on_existing(args.resume), &settings, &poses, &target)?;
    if args.resume && store.is_new() {
        Terminal.note(&format!(
            "note: nothing to resume: {} held no checkpoint, so every frame is baked",
            dir.display()
        ));
    }
    let transfer = store.bake_at(&poses, &target, frame, &Terminal)?;
    if let Some(path) = &args.points {
        write_npy(path, &[points.len(), POINT_COLUMNS], &point_table(&points))?;
    }
    let n2 = settings.order * settings.order;
    write_npy(
        &args.npy,
        &[poses.len(), points.len(), n2],
        &transfer.concat(),
    )?;
    store.remove()?;
    Ok(())
}

/// The rows of the `--points` file, one per point: triangle, barycentric coordinates, weight.
fn point_table(points: &SurfacePoints) -> Vec<f32> {
    points
        .points
        .iter()
        .flat_map(|p| {
            let [a, b, c] = p.bary;
            [p.triangle as f32, a, b, c, p.weight as f32]
        })
        .collect()
}
