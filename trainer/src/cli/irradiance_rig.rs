//! `aprt irradiance-rig`: fit an irradiance rig to a mesh or a character and report, for a lights file,
//! each light's path, the error against exact evaluation and the core's cost per frame.

use anyhow::{Context, Result, bail};

use crate::cli::args::RigArgs;
use crate::cli::stdout::outln;
use crate::cli::terminal::Terminal;
use crate::io::outputs::{Input, check};
use crate::irradiance_rig::fit::fitting_meshes;
use crate::irradiance_rig::{RigEvaluation, RigSettings, evaluate_rig, fit_rig};
use crate::lighting::read_lights;
use crate::model::runtime::{FrameCost, rig_frame_cost};
use crate::rig::mesh::Mesh;

/// The meshes the rig is fitted over and the mesh it is evaluated on.
fn meshes(args: &RigArgs) -> Result<(Vec<Mesh>, Mesh)> {
    let sequence = [
        ("--obj-seq", &args.source.obj_seq),
        ("--angles", &args.source.angles),
    ];
    if let Some((flag, Some(path))) = sequence.iter().find(|(_, path)| path.is_some()) {
        bail!(
            "{flag} {}: irradiance-rig fits a rig to one mesh (give one OBJ file of the sequence) or to a character (--builtin, --gltf, --bvh), not to an OBJ sequence",
            path.display()
        );
    }
    if args.mesh.is_some() && args.frame != 0 {
        bail!(
            "--frame {}: a mesh has one pose; --frame picks a frame of a character's clip",
            args.frame
        );
    }
    match (&args.mesh, args.source.names_rig()) {
        (Some(_), true) => bail!("give a mesh or a character (--builtin, --gltf, --bvh), not both"),
        (Some(path), false) => {
            let mesh = crate::io::obj::read_obj(path)?;
            Ok((vec![mesh.clone()], mesh))
        }
        (None, true) => {
            let (rig, clip) = args.source.rig(&Terminal)?;
            let Some(pose) = clip.frames.get(args.frame) else {
                bail!(
                    "--frame {}: clip {} has {} frames",
                    args.frame,
                    clip.name,
                    clip.frames.len()
                );
            };
            let posed = args.source.in_origin(rig.pose(pose))?;
            let fitting = args.source.in_origin(fitting_meshes(rig.as_ref(), &clip))?;
            Ok((fitting, posed))
        }
        (None, false) => bail!("give a mesh (OBJ) or a character (--builtin, --gltf or --bvh)"),
    }
}

/// The flags no input can make valid, refused before any file is read. `--samples` is held to
/// the core's limit on a rig's sample points, which would otherwise refuse the rig only after
/// minutes of fitting (or, near `usize::MAX`, the allocation would abort the run).
fn check_flags(args: &RigArgs) -> Result<()> {
    if !(args.target_error.is_finite() && args.target_error > 0.0) {
        bail!(
            "--target-error {}: give a positive number of grey levels",
            args.target_error
        );
    }
    if let Some(n) = args.samples
        && !(1..=aprt_core::MAX_RIG_SAMPLES).contains(&n)
    {
        bail!(
            "--samples {n}: a rig is fitted over 1 to {} surface samples (the most the runtime's rig holds)",
            aprt_core::MAX_RIG_SAMPLES
        );
    }
    Ok(())
}

/// Runs `aprt irradiance-rig`.
pub fn run(args: &RigArgs) -> Result<()> {
    let mut inputs = args.source.inputs();
    inputs.push(Input::new(&args.lights, "the lights file"));
    if let Some(mesh) = &args.mesh {
        inputs.push(Input::new(mesh, "the mesh"));
    }
    check_flags(args)?;
    check(&[], &inputs)?;
    let lights = read_lights(&args.lights)?;
    let (fitting, posed) = meshes(args)?;
    let settings = RigSettings {
        order: args.order as usize,
        target_error: args.target_error,
        ..RigSettings::default()
    };
    let refs: Vec<&Mesh> = fitting.iter().collect();
    let mut fitted = fit_rig(args.rig, &refs, args.samples);
    fitted
        .tabulate(&posed, settings.order)
        .context("tabulating the rig's error")?;
    let evaluation = evaluate_rig(&fitted, &posed, &lights, &settings)
        .with_context(|| format!("{}", args.lights.display()))?;
    let us_per_frame = rig_frame_cost(
        &fitted,
        &posed,
        &lights,
        &evaluation.shares(),
        settings.order,
    )
    .with_context(|| format!("{}: timing the rig", args.lights.display()))?;
    let report = RigReport {
        evaluation,
        us_per_frame,
    };
    if args.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&report).context("writing JSON")?
        )?;
    } else {
        print_report(&report)?;
    }
    Ok(())
}

/// What `aprt irradiance-rig` reports: the rig's evaluation and, beside it, what it costs the core.
#[derive(serde::Serialize)]
struct RigReport {
    #[serde(flatten)]
    evaluation: RigEvaluation,
    /// aprt-core's cost per frame for the rig's share.
    us_per_frame: FrameCost,
}

fn print_report(report: &RigReport) -> Result<()> {
    let r = &report.evaluation;
    outln!(
        "rig {}: {} SH vectors from {} surface samples, order {}, {} vertices, radius {:.3}",
        r.rig,
        r.sh_vectors,
        r.samples,
        r.order,
        r.vertices,
        r.radius
    )?;
    for l in &r.lights {
        let distance = l
            .distance
            .map_or("at infinity".into(), |d| format!("at {d:.3}"));
        outln!(
            "  light {} ({}) {distance}: {} (rig share {:.2}, transition distance {:.3})",
            l.index,
            l.kind,
            l.mode,
            l.rig_share,
            l.transition_distance
        )?;
    }
    let g = |e: crate::irradiance_rig::GreyError| format!("mean {:.3}, max {:.3}", e.mean, e.max);
    outln!(
        "  error against exact, grey levels (target {}):",
        r.target_error
    )?;
    outln!("    as chosen            {}", g(r.error_grey))?;
    outln!("    every light in rig   {}", g(r.error_grey_all_rig))?;
    outln!(
        "    every light per vertex (SH floor) {}",
        g(r.error_grey_per_vertex)
    )?;
    let c = report.us_per_frame;
    outln!(
        "  aprt-core per frame: {:.1} us rig vectors + {:.1} us rig shading + {:.1} us per-vertex lights = {:.1} us",
        c.rig_vectors,
        c.shade,
        c.analytic,
        c.total
    )
}
