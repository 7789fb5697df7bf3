//! How the joint reference's velocity moves toward the velocity an
//! avoidance law asks for, one control period at a time: a slew limit (the
//! paper's law, `control.reference_accel_limit`), or a slew and a jerk
//! limit (the barrier filter's, `[avoidance] accel_limit` and
//! `jerk_limit`). The computed-torque law feeds the reference's
//! acceleration forward (`τ = M q̈_ref + …`), so a slew alone steps the
//! torque by up to `M · 2 a_max` in one period whenever the asked velocity
//! turns (at 30 rad/s², 45-150 Nm at each depth frame on the three arms);
//! the jerk limit bounds the step to about `M · j_max · dt`.

/// `v` \[rad/s\] toward `target` by at most `dv` \[rad/s\] (`∞`: at once).
pub fn slew(v: &mut f64, target: f64, dv: f64) {
    *v += (target - *v).clamp(-dv, dv);
}

/// One period `dt` \[s\] of `v` \[rad/s\], whose acceleration was `a`
/// \[rad/s²\] last period, toward `target` \[rad/s\]: the acceleration
/// changes by at most `jerk · dt` (`jerk` \[rad/s³\]) and stays within
/// `±a_max` \[rad/s²\]. Of a step up, none and a step down it takes the
/// largest that still lets the acceleration ramp back to 0 without passing
/// `target`, and lands on `target` once one period's change reaches it
/// with an acceleration that can stop there: time-optimal within a period,
/// without overshoot. Writes the new acceleration into `a`. A non-finite or
/// non-positive `jerk`, `a_max` or `dt` is the plain [`slew`] by
/// `a_max · dt`, `a` then the step taken.
pub fn slew_jerk(v: &mut f64, a: &mut f64, target: f64, (a_max, jerk): (f64, f64), dt: f64) {
    let usable = |x: f64| x.is_finite() && x > 0.0;
    if !(usable(jerk) && usable(a_max) && usable(dt) && a.is_finite() && target.is_finite()) {
        let before = *v;
        slew(v, target, a_max * dt);
        *a = match usable(dt) {
            true => (*v - before) / dt,
            false => 0.0,
        };
        return;
    }
    let e = target - *v;
    if e == 0.0 && *a == 0.0 {
        return;
    }
    // in the error's direction: the error still to gain, the acceleration
    let s = if e > 0.0 || (e == 0.0 && *a < 0.0) {
        1.0
    } else {
        -1.0
    };
    let (gain, acc) = (s * e, s * *a);
    let step = jerk * dt;
    let land = gain / dt;
    let next = if (land - acc).abs() <= step * (1.0 + 1e-9) && land <= step * (1.0 + 1e-9) {
        land
    } else {
        [acc + step, acc, acc - step]
            .into_iter()
            .map(|c| c.clamp(-a_max, a_max))
            .find(|&c| c * dt + coast(c, step, dt) <= gain * (1.0 + 1e-12))
            .unwrap_or((acc - step).max(-a_max))
    };
    *a = s * next;
    *v += *a * dt;
}

/// The velocity \[rad/s\] an acceleration `c` \[rad/s²\] still adds while it
/// ramps to 0 by `step` \[rad/s²\] a period of `dt` \[s\] (negative for a
/// negative `c`).
fn coast(c: f64, step: f64, dt: f64) -> f64 {
    let m = ((c.abs() / step).ceil() - 1.0).max(0.0);
    c.signum() * dt * (m * c.abs() - step * m * (m + 1.0) / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1e-3;
    const LIMITS: (f64, f64) = (30.0, 3000.0);

    /// Runs `v` toward `target(k)` for `periods`; checks every period's
    /// acceleration and jerk against the limits. Returns (v, a) per period.
    fn run(v0: f64, target: impl Fn(usize) -> f64, periods: usize) -> Vec<(f64, f64)> {
        let (mut v, mut a) = (v0, 0.0);
        let mut out = Vec::new();
        for k in 0..periods {
            let before = a;
            slew_jerk(&mut v, &mut a, target(k), LIMITS, DT);
            assert!(a.abs() <= LIMITS.0 + 1e-9, "period {k}: a {a}");
            assert!(
                (a - before).abs() <= LIMITS.1 * DT + 1e-9,
                "period {k}: jerk {}",
                (a - before) / DT
            );
            out.push((v, a));
        }
        out
    }

    #[test]
    fn a_step_in_the_asked_velocity_is_reached_without_overshoot_within_its_limits() {
        for target in [1.0, -0.4, 0.05, 2.5, 1e-4] {
            let out = run(0.0, |_| target, 400);
            // the fastest time: ramp up, hold a_max, ramp down (or a triangle)
            let (a_max, j) = LIMITS;
            let ramp = (a_max / j).min((target.abs() / j).sqrt());
            let t_min = 2.0 * ramp + (target.abs() / a_max - a_max / j).max(0.0);
            let reached = out
                .iter()
                .position(|(v, a)| (v - target).abs() < 1e-9 && a.abs() < 1e-9)
                .expect("reached");
            let t = (reached + 1) as f64 * DT;
            assert!(
                t < t_min + 0.003,
                "target {target}: {t} s against {t_min} s"
            );
            for (k, (v, _)) in out.iter().enumerate() {
                assert!(
                    v * target.signum() <= target.abs() + 1e-12,
                    "target {target}: overshoot {v} at period {k}"
                );
            }
            // and stays there, at rest
            assert!(out[reached..]
                .iter()
                .all(|(v, a)| (v - target).abs() < 1e-9 && *a == 0.0));
        }
    }

    #[test]
    fn a_target_that_turns_mid_ramp_is_followed_within_the_limits() {
        // the filter's answer jumping at each depth frame (30 Hz)
        let target = |k: usize| if (k / 33) % 2 == 0 { 0.6 } else { -0.3 };
        let out = run(0.0, target, 2000);
        assert!(out
            .iter()
            .all(|(v, _)| (-0.3 - 1e-12..=0.6 + 1e-12).contains(v)));
        // a constant target after the turns is reached
        let out = run(out.last().unwrap().0, |_| 0.2, 200);
        assert!((out.last().unwrap().0 - 0.2).abs() < 1e-9);
    }

    #[test]
    fn without_a_usable_jerk_limit_it_is_the_slew() {
        for jerk in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let (mut v, mut a) = (0.0, 5.0);
            slew_jerk(&mut v, &mut a, 1.0, (30.0, jerk), DT);
            assert!((v - 0.03).abs() < 1e-12, "{jerk}: {v}");
            assert!((a - 30.0).abs() < 1e-9, "{jerk}: {a}");
        }
        let mut v = 0.0;
        slew(&mut v, -1.0, 0.03);
        assert_eq!(v, -0.03);
        slew(&mut v, 5.0, f64::INFINITY);
        assert_eq!(v, 5.0);
    }
}
