//! `phri-plot`'s figures of a recording's [`Series`], one function each:
//! the end-effector path (the paper's Fig. 7), the momentum residual, the
//! minimum distance and, with a collaboration, the end effector and the
//! hand over time (Figs. 8 and 11) and the contact force.

use std::path::Path;

use crate::plot::{range, Axes, Figure, FigureError, Format, Rgb, BLUE, GREY, ORANGE, RED};
use crate::series::Series;

const GREEN: Rgb = [44, 160, 44];
const PURPLE: Rgb = [148, 103, 189];
const BROWN: Rgb = [140, 86, 75];
/// Every figure's size [px].
const W: usize = 900;
const H: usize = 600;
/// Samples further apart than this [s] are drawn as separate lines.
const GAP_S: f64 = 0.2;

/// Writes every figure of `series` into `out` as `format`: the threshold
/// \[Nm\] on the residual's when known, the path `without` the person \[m\]
/// under the end effector's (empty: none); the collaboration's two only
/// when the recording has one.
pub fn save_all(
    series: &Series,
    threshold: Option<f64>,
    without: &[(f64, f64)],
    out: &Path,
    format: Format,
) -> Result<(), FigureError> {
    ee_trajectory(series, without).save(out, "ee_trajectory", format)?;
    residual(series, threshold).save(out, "residual", format)?;
    min_distance(series).save(out, "min_distance", format)?;
    if series.collaborated {
        collaboration(series).save(out, "collaboration", format)?;
        contact_force(series).save(out, "contact_force", format)?;
    }
    Ok(())
}

/// The end effector's x-y path at equal scale on both axes, blue while the
/// person is far, red while near, the path `without` the person in grey
/// beneath.
pub fn ee_trajectory(series: &Series, without: &[(f64, f64)]) -> Figure {
    let mut c = Figure::new(W, H);
    let ee = &series.ee;
    let xs = || ee.iter().map(|p| p.0).chain(without.iter().map(|p| p.0));
    let ys = || ee.iter().map(|p| p.1).chain(without.iter().map(|p| p.1));
    let (Some(xr), Some(yr)) = (range(xs()), range(ys())) else {
        return c;
    };
    let a = equal_scale(&c, xr, yr);
    a.draw(&mut c);
    a.label(&mut c, "end-effector path", "x [m]", "y [m]");
    let mut legend = vec![
        (BLUE, "person farther than 0.4 m"),
        (RED, "person within 0.4 m"),
    ];
    if !without.is_empty() {
        legend.push((GREY, "without the person"));
    }
    a.legend(&mut c, &legend);
    a.polyline(&mut c, without, GREY);
    // contiguous runs of the same presence, each in its colour
    let mut run: Vec<(f64, f64)> = Vec::new();
    let mut near = false;
    for &(x, y, n) in ee {
        if n != near && !run.is_empty() {
            a.polyline(&mut c, &run, if near { RED } else { BLUE });
            let last = run[run.len() - 1];
            run.clear();
            run.push(last);
        }
        near = n;
        run.push((x, y));
    }
    a.polyline(&mut c, &run, if near { RED } else { BLUE });
    c
}

/// Axes over the ranges `xr`, `yr` widened to one scale [m/px] on both.
fn equal_scale(c: &Figure, xr: (f64, f64), yr: (f64, f64)) -> Axes {
    let probe = Axes::new(c, xr, yr);
    let (pw, ph) = (
        (probe.right - probe.left) as f64,
        (probe.bottom - probe.top) as f64,
    );
    let scale = ((xr.1 - xr.0) / pw).max((yr.1 - yr.0) / ph);
    let (cx, cy) = ((xr.0 + xr.1) / 2.0, (yr.0 + yr.1) / 2.0);
    Axes::new(
        c,
        (cx - scale * pw / 2.0, cx + scale * pw / 2.0),
        (cy - scale * ph / 2.0, cy + scale * ph / 2.0),
    )
}

/// ‖r‖ over time, the threshold dashed when known, a vertical line at each
/// collision detected.
pub fn residual(series: &Series, threshold: Option<f64>) -> Figure {
    let mut c = Figure::new(W, H);
    let norm = &series.norm;
    let (Some(xr), Some(yr)) = (
        range(norm.iter().map(|p| p.0)),
        range(norm.iter().map(|p| p.1).chain(threshold).chain([0.0])),
    ) else {
        return c;
    };
    let a = Axes::new(&c, xr, yr);
    a.draw(&mut c);
    a.label(&mut c, "momentum residual", "t [s]", "‖r‖ [Nm]");
    let mut legend = vec![(BLUE, "‖r‖")];
    if threshold.is_some() {
        legend.push((RED, "threshold"));
    }
    if !series.rises.is_empty() {
        legend.push((ORANGE, "collision detected"));
    }
    a.legend(&mut c, &legend);
    for &t in &series.rises {
        a.vline(&mut c, t, ORANGE);
    }
    if let Some(th) = threshold {
        a.hline(&mut c, th, RED);
    }
    a.polyline(&mut c, norm, BLUE);
    c
}

/// The controller's minimum distance over time.
pub fn min_distance(series: &Series) -> Figure {
    let mut c = Figure::new(W, H);
    let dist = &series.dist;
    if let (Some(xr), Some(yr)) = (
        range(dist.iter().map(|p| p.0)),
        range(dist.iter().map(|p| p.1).chain([0.0])),
    ) {
        let a = Axes::new(&c, xr, yr);
        a.draw(&mut c);
        a.label(
            &mut c,
            "minimum distance, depth space",
            "t [s]",
            "distance [m]",
        );
        a.polyline(&mut c, dist, BLUE);
    }
    c
}

/// Figs. 8/11: end effector (solid colours) and hand (darker) x, y, z over
/// time, a grey line at each change of phase.
pub fn collaboration(series: &Series) -> Figure {
    let mut c = Figure::new(W, H);
    let all = || series.ee_t.iter().chain(series.hand_t.iter()).flatten();
    let (Some(xr), Some(yr)) = (range(all().map(|p| p.0)), range(all().map(|p| p.1))) else {
        return c;
    };
    let a = Axes::new(&c, xr, yr);
    a.draw(&mut c);
    a.label(
        &mut c,
        "end effector and collaborative hand",
        "t [s]",
        "position [m]",
    );
    a.legend(
        &mut c,
        &[
            (BLUE, "end effector x"),
            (RED, "end effector y"),
            (ORANGE, "end effector z"),
            (GREEN, "hand x"),
            (PURPLE, "hand y"),
            (BROWN, "hand z"),
            (GREY, "change of phase"),
        ],
    );
    let changes = &series.phase_changes;
    for (t, _) in &changes[1.min(changes.len())..] {
        a.vline(&mut c, *t, GREY);
    }
    for (s, col) in series.ee_t.iter().zip([BLUE, RED, ORANGE]) {
        a.polyline(&mut c, s, col);
    }
    // the hand only while collaborating: one line per stretch
    for (s, col) in series.hand_t.iter().zip([GREEN, PURPLE, BROWN]) {
        for run in s.chunk_by(|p, q| q.0 - p.0 < GAP_S) {
            a.polyline(&mut c, run, col);
        }
    }
    c
}

/// The estimated (eqs. 21-22) against the true (simulator) contact force of
/// the collaborative hand.
pub fn contact_force(series: &Series) -> Figure {
    let mut c = Figure::new(W, H);
    let (f_est, f_true) = (&series.f_est, &series.f_true);
    let all = || f_est.iter().chain(f_true.iter());
    if let (Some(xr), Some(yr)) = (
        range(all().map(|p| p.0)),
        range(all().map(|p| p.1).chain([0.0])),
    ) {
        let a = Axes::new(&c, xr, yr);
        a.draw(&mut c);
        a.label(
            &mut c,
            "contact force of the collaborative hand",
            "t [s]",
            "force [N]",
        );
        a.legend(
            &mut c,
            &[(RED, "true (simulator)"), (BLUE, "estimated (eqs. 21-22)")],
        );
        a.polyline(&mut c, f_true, RED);
        for run in f_est.chunk_by(|p, q| q.0 - p.0 < GAP_S) {
            a.polyline(&mut c, run, BLUE);
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_figure_is_drawn_even_without_data() {
        let empty = Series::default();
        for f in [
            ee_trajectory(&empty, &[]),
            residual(&empty, Some(5.0)),
            min_distance(&empty),
            collaboration(&empty),
            contact_force(&empty),
        ] {
            assert_eq!((f.w(), f.h()), (W, H));
        }
    }

    #[test]
    fn the_path_keeps_equal_scale_on_both_axes() {
        let c = Figure::new(W, H);
        let a = equal_scale(&c, (0.0, 1.0), (0.0, 0.1));
        let x = (a.fx(1.0) - a.fx(0.0)).abs();
        let y = (a.fy(1.0) - a.fy(0.0)).abs();
        assert!((x - y).abs() < 1e-9 * x, "{x} px/m across, {y} px/m up");
    }

    #[test]
    fn only_a_collaboration_adds_its_figures() {
        let dir = std::env::temp_dir().join(format!("phri-figures-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut s = Series::default();
        save_all(&s, None, &[], &dir, Format::Svg).unwrap();
        assert!(dir.join("ee_trajectory.svg").exists());
        assert!(!dir.join("collaboration.svg").exists());
        s.collaborated = true;
        save_all(&s, None, &[], &dir, Format::Svg).unwrap();
        assert!(dir.join("contact_force.svg").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
