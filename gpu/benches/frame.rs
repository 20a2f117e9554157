//! A frame on the device beside the same frame on aprt-core's CPU evaluator, on whatever
//! adapter `Gpu::new` finds. The model is the built-in character's (bone frames, occluder
//! proxies, 13,022 vertices) in f32, f16 and i8 rows, trained by the root workspace's `aprt`
//! as `tests/kernels.rs` trains it, or the model file `$APRT_BENCH_MODEL` (a relative path is
//! taken from `gpu/`, where cargo runs a bench).
//!
//! Both sides pay the per-frame weights on the CPU (`Model::set_pose`, and `Model::light` for
//! shading). Then the CPU runs `Model::shade` or `Model::transfer` over every vertex on one
//! core, and the device uploads the weights, runs the kernel and is waited for (`Gpu::wait`),
//! or reads the output back. A model with occluder proxies also times the frame it ships:
//! shading, the proxies posed on the CPU (`Model::pose_proxies`, both sides), then their
//! correction (`Model::occlude`, or `GpuModel::occlude`), at vertices placed around the
//! proxies. The steps run in interleaved rounds and each figure is a median
//! of per-round figures, as the root workspace's benches time theirs, so the machine's drift
//! cancels. `cargo bench --manifest-path gpu/Cargo.toml --bench frame`.

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "../../tests/src/timing.rs"]
mod timing;

use std::hint::black_box;
use std::time::Duration;

use aprt_core::{LitWeights, Model, PoseWeights, ProxyFrame, Rotation};
use aprt_gpu::{Gpu, GpuModel};
use common::{
    BUILTIN_RIGS, BUILTIN_TRAIN, builtin_models, gpu_or_skip, rotations, skinning, trainer,
    vertices_near_proxies,
};
use timing::{interleaved_seconds, median_ratio};

const ROUNDS: usize = 15;
/// Per model, shared by its six steps.
const BUDGET: Duration = Duration::from_secs(6);

fn main() {
    let bench = "frame bench";
    let Some(gpu) = gpu_or_skip(bench) else {
        return;
    };
    println!("adapter: {gpu}");
    if gpu.info().device_type == wgpu::DeviceType::Cpu {
        println!(
            "  a software adapter: the kernels run on this machine's CPU cores (possibly \
             several threads), so these figures only show that the path runs, not what a GPU does"
        );
    }
    let models = match std::env::var_os("APRT_BENCH_MODEL") {
        Some(path) => {
            println!("model: {} ($APRT_BENCH_MODEL)", path.display());
            let blob =
                std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.to_string_lossy()));
            vec![("model", blob)]
        }
        None => {
            let Some(aprt) = trainer(bench) else {
                return;
            };
            let rigs: Vec<String> = BUILTIN_RIGS
                .iter()
                .map(|(precision, rig)| format!("--rig {rig} --precision {precision}"))
                .collect();
            println!(
                "model: the built-in character, `{} {BUILTIN_TRAIN}` with {}",
                aprt.display(),
                rigs.join(" | ")
            );
            builtin_models(&aprt)
        }
    };
    println!(
        "CPU: aprt-core, one core. Per frame: weights on the CPU (set_pose, and light for \
         shading), then every vertex; medians of {ROUNDS} interleaved rounds"
    );
    let mut rows = Vec::new();
    for (name, blob) in &models {
        let model = Model::parse(blob).expect("a valid model");
        let info = model.info();
        println!(
            "{name}: {} vertices, order {}, k_a {}, k_v {}, {:?} rows, {} bones{}",
            info.vertices(),
            info.order(),
            info.pose_dims(),
            info.coef_dims(),
            info.encoding(),
            info.bones(),
            if info.has_proxies() {
                ", occluder proxies"
            } else {
                ""
            }
        );
        rows.extend(time_model(&gpu, name, &model));
    }
    println!(
        "\n{:<22} {:>10} {:>10} {:>12} {:>10} {:>13}",
        "frame", "CPU µs", "GPU µs", "GPU+read µs", "GPU/CPU", "GPU+read/CPU"
    );
    for row in rows {
        println!("{row}");
    }
}

/// A frame's inputs, the same every frame, and the CPU work both sides pay for them.
struct Frame<'m> {
    model: &'m Model<'m>,
    angles: Vec<f32>,
    lighting: Vec<f32>,
    bones: Vec<Rotation>,
}

/// One step's own weights: the steps' closures are alive together.
struct Weights {
    pose: Box<PoseWeights>,
    lit: Box<LitWeights>,
}

impl Frame<'_> {
    /// The pose weights of the frame, into `w`.
    fn pose<'w>(&self, w: &'w mut Weights) -> &'w PoseWeights {
        self.model
            .set_pose(black_box(&self.angles), &mut w.pose)
            .unwrap();
        &w.pose
    }

    /// The pose and lighting weights of the frame, into `w`.
    fn lit<'w>(&self, w: &'w mut Weights) -> &'w LitWeights {
        self.model
            .set_pose(black_box(&self.angles), &mut w.pose)
            .unwrap();
        let lighting = black_box(&self.lighting);
        self.model
            .light(&w.pose, lighting, &self.bones, &mut w.lit)
            .unwrap();
        &w.lit
    }
}

/// Shading, transfer and (for a model with occluder proxies) the shading they correct, on
/// both sides, interleaved in one run: the table's rows for the model.
fn time_model(gpu: &Gpu, name: &str, model: &Model<'_>) -> Vec<String> {
    let info = *model.info();
    let on_gpu = GpuModel::upload(gpu, model).expect("the model fits the device");
    let bones = rotations(info.bones());
    let frame = Frame {
        model,
        angles: (0..info.pose_len())
            .map(|i| 0.4 * (i as f32 * 1.7).sin())
            .collect(),
        lighting: (0..info.coeffs()).map(|c| 1.0 / (1.0 + c as f32)).collect(),
        bones: bones.clone(),
    };
    // The proxies' frame inputs: posed every frame from the bones' skinning, the skinned
    // vertices placed around them (a frame of the engine's mesh has them in reach as often).
    let skin = skinning(&bones);
    let mut proxies = ProxyFrame::new();
    let vertices = match info.has_proxies() {
        true => {
            model.pose_proxies(&skin, &mut proxies).unwrap();
            Some(vertices_near_proxies(model, &proxies))
        }
        false => None,
    };
    let mut weights: [Weights; 8] = std::array::from_fn(|_| Weights {
        pose: Box::new(PoseWeights::new()),
        lit: Box::new(LitWeights::new()),
    });
    let [w0, w1, w2, w3, w4, w5, w6, w7] = &mut weights;
    let mut shading = vec![0f32; info.vertices()];
    let mut occluded = vec![0f32; info.vertices()];
    let mut transfer = vec![0f32; info.vertices() * info.coeffs()];
    let (mut cpu_frame, mut gpu_frame) = (ProxyFrame::new(), ProxyFrame::new());
    let mut steps: Vec<&mut dyn FnMut()> = Vec::new();
    let mut cpu_shade = || {
        model
            .shade(frame.lit(w0), 0, black_box(&mut shading))
            .unwrap()
    };
    let mut gpu_shade = || {
        on_gpu.shade(gpu, frame.lit(w1)).unwrap();
        gpu.wait().unwrap();
    };
    let mut gpu_shade_read = || {
        on_gpu.shade(gpu, frame.lit(w2)).unwrap();
        black_box(on_gpu.read_shading(gpu).unwrap());
    };
    let mut cpu_transfer = || {
        model
            .transfer(frame.pose(w3), 0, black_box(&mut transfer))
            .unwrap()
    };
    let mut gpu_transfer = || {
        on_gpu.transfer(gpu, frame.pose(w4)).unwrap();
        gpu.wait().unwrap();
    };
    let mut gpu_transfer_read = || {
        on_gpu.transfer(gpu, frame.pose(w5)).unwrap();
        black_box(on_gpu.read_transfer(gpu).unwrap());
    };
    steps.extend([
        &mut cpu_shade as &mut dyn FnMut(),
        &mut gpu_shade,
        &mut gpu_shade_read,
        &mut cpu_transfer,
        &mut gpu_transfer,
        &mut gpu_transfer_read,
    ]);
    let mut cpu_occlude;
    let mut gpu_occlude;
    if let Some((positions, normals)) = &vertices {
        let lighting = &frame.lighting;
        cpu_occlude = || {
            model
                .shade(frame.lit(w6), 0, black_box(&mut occluded))
                .unwrap();
            model.pose_proxies(&skin, &mut cpu_frame).unwrap();
            model
                .occlude(&cpu_frame, lighting, positions, normals, 0, &mut occluded)
                .unwrap();
        };
        gpu_occlude = || {
            on_gpu.shade(gpu, frame.lit(w7)).unwrap();
            model.pose_proxies(&skin, &mut gpu_frame).unwrap();
            on_gpu
                .occlude(gpu, (&gpu_frame, lighting), (positions, normals))
                .unwrap();
            gpu.wait().unwrap();
        };
        steps.extend([&mut cpu_occlude as &mut dyn FnMut(), &mut gpu_occlude]);
    }
    let times = interleaved_seconds(BUDGET, ROUNDS, &mut steps);
    let us = |t: &[f64]| median_ratio(t, &[1e-6; ROUNDS]);
    let row = |what: &str, cpu: &[f64], dispatch: &[f64], read: Option<&[f64]>| {
        let (read_us, read_ratio) = match read {
            Some(read) => (
                format!("{:>12.1}", us(read)),
                format!("{:>12.2}x", median_ratio(read, cpu)),
            ),
            None => (format!("{:>12}", "–"), format!("{:>13}", "–")),
        };
        format!(
            "{:<22} {:>10.1} {:>10.1} {read_us} {:>9.2}x {read_ratio}",
            format!("{name} {what}"),
            us(cpu),
            us(dispatch),
            median_ratio(dispatch, cpu),
        )
    };
    let mut rows = vec![
        row("shade", &times[0], &times[1], Some(&times[2])),
        row("transfer", &times[3], &times[4], Some(&times[5])),
    ];
    if vertices.is_some() {
        rows.push(row("shade + proxies", &times[6], &times[7], None));
    }
    rows
}
