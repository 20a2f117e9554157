//! The study's README: what was run, the tables, the plots, the renders, the claim.

use std::fmt::Write;

use super::measure::{Agg, Cell, Measured};
use super::setup::{DISTANCES, LASH_FRAME, LIGHT_RADIUS, NOVEL_FRAMES};
use super::setup::{LATTICE_64, MIXED_6};
use super::{COMPARABLE, ClaimEntry, sweep_index};

fn cell(c: &Agg) -> String {
    format!("{:.2} / {:.1}", c.mean, c.max)
}

/// The error table on `lash` (from the sweep) or on the bind pose, against exact (with the SH
/// floor's row) or against per-vertex SH.
fn error_table(m: &Measured, lash: bool, against_exact: bool) -> String {
    let measure = |c: &Cell| -> Agg {
        if against_exact {
            c.exact.clone()
        } else {
            c.added.clone()
        }
    };
    let mut s = String::from(
        "| rig (`--rig`, creature axes) | paper's rig (length, height, width) | SH vectors \
         | near 1.25 R | mid 2.5 R | far 8 R | µs / frame |\n\
         | --- | --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    let pick = |aggs: Vec<Agg>, k: usize| -> String {
        let i = if lash {
            sweep_index(m, DISTANCES[k].1)
        } else {
            Some(k)
        };
        i.and_then(|i| aggs.get(i)).map_or("–".into(), cell)
    };
    for r in &m.rigs {
        let us = r.us_per_frame.map_or("–".into(), |u| format!("{u:.0}"));
        let cells = if lash { &r.lash } else { &r.bind };
        let aggs = || cells.iter().map(measure).collect::<Vec<_>>();
        let _ = writeln!(
            s,
            "| `{}` | {} | {} | {} | {} | {} | {us} |",
            r.choice.kind,
            r.choice.paper,
            r.sh_vectors,
            pick(aggs(), 0),
            pick(aggs(), 1),
            pick(aggs(), 2)
        );
    }
    if !against_exact {
        return s;
    }
    let floor = || if lash { &m.floor_lash } else { &m.floor_bind }.clone();
    let _ = writeln!(
        s,
        "| per vertex (SH floor) | every light through SH at each vertex | – | {} | {} | {} | – |",
        pick(floor(), 0),
        pick(floor(), 1),
        pick(floor(), 2)
    );
    s
}

fn claim_section(claim: &[ClaimEntry]) -> String {
    let mut s = String::from(
        "| distance | direction | mixed (6) added | lattice (64) added | ratio \
         | mixed vs exact | lattice vs exact | ratio |\n\
         | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for c in claim {
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.2} | {:.2}{} | {:.2} | {:.2} | {:.2} |",
            c.distance,
            c.direction,
            c.added_max[0],
            c.added_max[1],
            c.ratio,
            if c.holds { "" } else { " ✗" },
            c.exact_max[0],
            c.exact_max[1],
            c.exact_ratio
        );
    }
    for (name, _) in DISTANCES {
        let here: Vec<&ClaimEntry> = claim.iter().filter(|c| c.distance == name).collect();
        let count = |f: &dyn Fn(&ClaimEntry) -> f64| {
            let holds = here.iter().filter(|c| f(c) <= COMPARABLE).count();
            let lo = here.iter().map(|c| f(c)).fold(f64::INFINITY, f64::min);
            let hi = here.iter().map(|c| f(c)).fold(0.0, f64::max);
            format!(
                "{holds} of {} directions (ratios {lo:.2} to {hi:.2})",
                here.len()
            )
        };
        let _ = write!(
            s,
            "\n- {name}: within {COMPARABLE}× of the lattice's largest added error in {}; \
             against exact, in {}.",
            count(&|c| c.ratio),
            count(&|c| c.exact_ratio)
        );
    }
    s.push('\n');
    s
}

fn novel_table(m: &Measured) -> String {
    let mut s = String::from(
        "| rig | lash, bind-only fit | lash, bind + training fit | prowl, bind-only fit \
         | prowl, bind + training fit |\n| --- | ---: | ---: | ---: | ---: |\n",
    );
    for r in &m.rigs {
        let Some(n) = &r.novel else { continue };
        let _ = writeln!(
            s,
            "| `{}` | {} | {} | {} | {} |",
            r.choice.kind,
            cell(&n.bind_only[0].added),
            cell(&n.bind_training[0].added),
            cell(&n.bind_only[1].added),
            cell(&n.bind_training[1].added)
        );
    }
    s
}

/// The rig's added error (worst, mean) at table distance `k` on `lash`.
fn added_at(m: &Measured, r: usize, k: usize) -> (f64, f64) {
    sweep_index(m, DISTANCES[k].1)
        .and_then(|i| m.rigs[r].lash.get(i))
        .map_or((f64::NAN, f64::NAN), |c| (c.added.max, c.added.mean))
}

/// What holds and what does not, with the numbers.
fn findings(m: &Measured) -> String {
    let mut s = String::from("## What holds and what does not\n\n");
    let rises: Vec<String> = (0..m.rigs.len())
        .filter(|&r| added_at(m, r, 1).0 > added_at(m, r, 0).0)
        .map(|r| format!("`{}`", m.rigs[r].choice.kind))
        .collect();
    let falls_far = (0..m.rigs.len()).all(|r| {
        let (mid, far) = (added_at(m, r, 1), added_at(m, r, 2));
        far.0 < mid.0 && far.1 < mid.1
    });
    let floor = |k: usize| sweep_index(m, DISTANCES[k].1).map_or(f64::NAN, |i| m.floor_lash[i].max);
    let heading = if rises.is_empty() {
        "Errors fall with distance from mid on"
    } else {
        "Errors do not fall with distance everywhere"
    };
    let _ = write!(
        s,
        "- **{heading}.** With the paper's normalisation \
         the light's strength grows as (d − 1)², and the creature is long and thin: its \
         bounding sphere (radius the half-length) is far from the flanks and the back, so a \
         near light is weak on most of the surface. The largest error each rig adds to \
         per-vertex SH rises from near (1.25 R) to mid (2.5 R) for {} of {} rigs ({}), and falls \
         from mid to far for {}.\n\
         - **The SH floor.** Per-vertex SH at order \
         {} is off by up to {:.1} / {:.1} / {:.1} grey levels near / mid / far on `lash`: the \
         order-3 clamped cosine misses about 9 % of the peak irradiance, and the normalised \
         light makes the peak white: no rig's error against exact can go below it.\n",
        rises.len(),
        m.rigs.len(),
        rises.join(", "),
        if falls_far {
            "every rig"
        } else {
            "some rigs only"
        },
        m.order,
        floor(0),
        floor(1),
        floor(2),
    );
    if m.rigs.len() > MIXED_6 {
        let (c, g) = (added_at(m, 0, 1), added_at(m, 1, 1));
        let (mx, lt) = (added_at(m, MIXED_6, 2), added_at(m, LATTICE_64, 2));
        let (lm, lx) = (added_at(m, MIXED_6 + 2, 1), added_at(m, LATTICE_64 + 2, 1));
        let (pm, pl) = (added_at(m, MIXED_6, 1), added_at(m, LATTICE_64, 1));
        let beats = if g.0 < c.0 { "beats" } else { "does not beat" };
        let (verdict, falls) = if mx.0 > lt.0 {
            ("is not comparable to", "adds more than")
        } else {
            ("matches", "adds no more than")
        };
        // The axes matter when spelling a rig in our axes changes its worst error by more
        // than a tenth.
        let differs = |ours: f64, paper: f64| (ours - paper).abs() > 0.1 * paper.max(ours);
        let axes = if differs(lm.0, pm.0) || differs(lx.0, pl.0) {
            "The axis choice matters"
        } else {
            "The axis choice barely matters"
        };
        let _ = write!(
            s,
            "- **The gradient {beats} the centroid probe** at mid distance: it adds {:.1} grey \
             levels at worst ({:.2} on average) where the constant rig adds {:.1} ({:.2}).\n\
             - **The six-vector mixed rig {verdict} the 64-vector lattice far away**: it \
             {falls} the lattice, {:.1} grey levels at worst ({:.2} on average) against \
             {:.1} ({:.2}).\n\
             - **{axes}**: spelled literally in our axes, the mixed rig adds {:.1} grey levels \
             at worst at mid distance (against {:.1} in the paper's axes) and the 8×4×2 lattice \
             {:.1} (against {:.1}).\n",
            g.0, g.1, c.0, c.1, mx.0, mx.1, lt.0, lt.1, lm.0, pm.0, lx.0, pl.0
        );
    }
    if let Some(n) = m.rigs.get(LATTICE_64).and_then(|r| r.novel.as_ref()) {
        let pair = |k: usize| {
            let (a, b) = (&n.bind_only[k].added, &n.bind_training[k].added);
            format!(
                "{:.2} / {:.1} → {:.2} / {:.1}",
                a.mean, a.max, b.mean, b.max
            )
        };
        // Whether the training poses lower the mean added error on each clip.
        let helps: Vec<bool> = (0..2)
            .map(|k| n.bind_training[k].added.mean < n.bind_only[k].added.mean)
            .collect();
        let verdict = match (helps[0], helps[1]) {
            (true, true) => "helps on both clips",
            (false, false) => "helps on neither clip",
            (true, false) => "helps on `lash` but not on `prowl`",
            (false, true) => "helps on `prowl` but not on `lash`",
        };
        let _ = write!(
            s,
            "- **Fitting over the training poses** instead of the bind pose alone {verdict}. \
             For `lattice:2x8x4` (mean / worst added error, bind-only → bind + training) it is \
             {} on `lash` and {} on `prowl` (table below).\n\n",
            pair(0),
            pair(1)
        );
    }
    s
}

/// The README.
pub fn markdown(m: &Measured, claim: &[ClaimEntry], command: &str, seconds: f64) -> String {
    let dirs: Vec<&str> = m.directions.iter().map(|d| d.name.as_str()).collect();
    let mut s = format!(
        "# Irradiance rigs on the creature\n\n\
         Generated by `{command}` ({seconds:.0} s on this machine; every figure but the µs \
         column is deterministic; the µs vary by tens of percent between runs on a shared \
         2-core machine). Raw numbers: [results.json](results.json).\n\n\
         ## Setup\n\n\
         - **Character**: the built-in creature, {} vertices, 4.2 m long along +y (tail tip \
         at +y, head at −y), z up, x across (its left is +x).\n\
         - **Rigs** are fitted with `fit_rig` over `fitting_meshes(creature, training)`: the \
         bind pose and {} training poses, root frame. Their box centre is \
         ({:.2}, {:.2}, {:.2}) m and their radius R = {:.3} m. The paper's axes are (length, \
         height, width); ours are (x across, y along, z up), so the paper's 8×4×2 is \
         `lattice:2x8x4`, its 2×2×3 with 3 along the length is `lattice:2x3x2` and its mixed \
         rig is `mixed:x=constant,y=lattice3,z=gradient`. `lattice:8x4x2` and \
         `mixed:x=lattice3,y=gradient,z=constant` are the same names read literally in our \
         axes (8 nodes and the 3-node lattice across the 0.6 m width).\n\
         - **Lights**: one sphere light at a time, radius {LIGHT_RADIUS} R, at d = 1.25 R \
         (near), 2.5 R (mid) or 8 R (far) from the rig centre, in {} directions: {}. Radiance is \
         normalised as in the paper's section 3.1: the light's far-field irradiance at the \
         nearest point of the bounding sphere, π r² L / ((d − 1) R)², is π, so a white \
         Lambertian surface there facing the light reflects radiance 1 (255 grey levels). Setting \
         `π r² L = (d − R)²` instead makes that irradiance 1, i.e. 81 grey levels: divide \
         every error here by π to get its numbers.\n\
         - **Error**: `error_grey_all_rig` of `irradiance_rig::accuracy`: every light in the rig, \
         SH order {}, against the exact horizon-clipped unshadowed irradiance at every vertex, \
         in 8-bit grey levels (255 |E_rig − E_exact| / π). Each cell is **mean / max**: the \
         mean over directions of the mean over vertices and channels, then the worst over \
         directions of the largest vertex error. \"per vertex (SH floor)\" evaluates the light \
         through SH at every vertex (`error_grey_per_vertex`): no rig can do better.\n\
         - **µs / frame**: `rig_vectors + shade` of `rig_frame_cost` \
         (aprt-core: the rig's vectors from its surface samples, then every vertex shaded \
         through a static model's transfer), the mid light beyond the tail, median of \
         repeated frames, one thread.\n\n",
        m.vertices,
        m.training_poses,
        m.centre[0],
        m.centre[1],
        m.centre[2],
        m.radius,
        dirs.len(),
        dirs.join(", "),
        m.order,
    );
    s.push_str(&findings(m));
    let _ = write!(
        s,
        "## Error on a novel pose (`lash` frame {LASH_FRAME}, the tail curled beside the left \
         flank)\n\n\
         Against the exact irradiance:\n\n{}\n\
         What the rig adds to per-vertex SH (every light in the rig against every light \
         through SH at each vertex; what the paper's Figure 5 and `FittedRig::tabulate` \
         measure, without the order-{} truncation both paths share):\n\n{}\n\
         ## Error on the bind pose\n\nAgainst exact:\n\n{}\nAdded to per-vertex SH:\n\n{}\n",
        error_table(m, true, true),
        m.order,
        error_table(m, true, false),
        error_table(m, false, true),
        error_table(m, false, false)
    );
    s.push_str(
        "## Error against distance\n\n\
         Like the paper's Figure 5, on the `lash` frame, against the light's distance from the \
         rig centre in radii, with the 1-grey-level line: what each rig adds to per-vertex \
         SH, then against exact with the SH floor; both the worst over directions of the \
         largest vertex error (the means are in the tables and results.json).\n\n\
         ![added error, worst](added_vs_distance_max.png)\n\
         ![error against exact, worst](exact_vs_distance_max.png)\n\n",
    );
    let _ = write!(
        s,
        "## The paper's claim: six vectors comparable to a 64-vector lattice\n\n\
         `mixed:x=constant,y=lattice3,z=gradient` against `lattice:2x8x4` on the `lash` \
         frame, light by light: the largest vertex error each adds to per-vertex SH (✗ where \
         the mixed rig's is more than {COMPARABLE}× the lattice's), then the largest against \
         exact.\n\n{}\n",
        claim_section(claim)
    );
    let _ = write!(
        s,
        "## Renders\n\n\
         ![renders](renders.png)\n\n\
         `lash` frame {LASH_FRAME} seen from its left (+x; head left, tail right, the curled \
         tail nearest the camera) under the mid light beyond the tail (2.5 R along +y). \
         Left: reflected radiance (white = 1, sRGB-encoded for display); right: |rig − exact| as a heat map, \
         blue 0 to red ≥ {} grey levels. First row: the exact lighting and the error of \
         per-vertex SH.\n\n",
        super::figures::HEAT_MAX
    );
    let frames = |k: usize| format!("{:?}", NOVEL_FRAMES[k].1);
    let _ = write!(
        s,
        "## Novel poses: fitted over the bind pose alone, or over bind + training\n\n\
         Mid distance (2.5 R, lights placed by the bind + training fit), every direction, \
         `lash` frames {} and `prowl` frames {}; mean / max as above over directions and \
         frames; the error each rig adds to per-vertex SH (results.json also has it against \
         exact).\n\n{}\n",
        frames(0),
        frames(1),
        novel_table(m)
    );
    s
}
