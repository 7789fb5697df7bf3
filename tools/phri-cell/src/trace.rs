//! A run's time series for diagnosis (`phri-lockstep --trace FILE`): one CSV
//! row per sample of what the controller saw and did beside the simulator's
//! ground truth, so that a figure of a summary (a waypoint missed, the
//! closest approach) can be traced to the moment and the parts involved.

use std::io::Write;

use phri_sim::contact::capsule_distance;

use crate::Cell;

/// The CSV header, one name per column (units in the names, base frame).
pub const HEADER: &str = "t_s,mode,ee_x_m,ee_y_m,ee_z_m,ref_x_m,ref_y_m,ref_z_m,waypoints,\
closest_true_m,closest_human_part,closest_robot_link,perceived_min_distance_m,risk,task_scale,\
collab_hand_x_m,collab_hand_y_m,collab_hand_z_m,collab_hand_error_m,collab_gap_m";

/// The closest human–robot capsule pair at the cell's state: surface
/// distance \[m\] (negative: penetrating), human part, robot link (`None`
/// without a person).
pub fn closest_pair(cell: &Cell) -> Option<(f64, &'static str, String)> {
    let mut best: Option<(f64, &'static str, usize)> = None;
    for h in cell.sim.human_capsules() {
        for r in cell.sim.robot_capsule_poses() {
            let d = capsule_distance(&h.a, &h.b, h.radius, &r.a, &r.b, r.radius).distance;
            if best.is_none_or(|b| d < b.0) {
                best = Some((d, h.part.name(), r.collision));
            }
        }
    }
    best.map(|(d, part, c)| {
        (
            d,
            part,
            cell.sim.collision_link(c).unwrap_or("").to_string(),
        )
    })
}

/// The collaboration's hand as the controller follows it \[m\], its distance
/// from the centre of the nearest hand of the simulated person \[m\], and the
/// gap to it that decides the phase \[m\] (`None` while no hand is followed).
fn collab_hand(cell: &Cell) -> Option<([f64; 3], f64, f64)> {
    let c = cell.controller.collaboration()?;
    let h = c.hand()?;
    let error = cell
        .sim
        .human_capsules()
        .iter()
        .filter(|k| matches!(k.part.name(), "hand_right" | "hand_left"))
        .map(|k| ((k.a + k.b) * 0.5 - h).norm())
        .fold(f64::INFINITY, f64::min);
    Some(([h.x, h.y, h.z], error, c.near_gap_m()))
}

/// One CSV row (no newline) of the cell after its last tick.
pub fn row(cell: &Cell) -> String {
    let s = &cell.status;
    let x_d = cell.controller.task_reference();
    let (d, part, link) = closest_pair(cell).unwrap_or((f64::INFINITY, "", String::new()));
    let collab = match collab_hand(cell) {
        Some((h, e, g)) => format!("{:.4},{:.4},{:.4},{e:.4},{g:.4}", h[0], h[1], h[2]),
        None => ",,,,".to_string(),
    };
    format!(
        "{:.3},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{},{:.4},{},{},{:.4},{:.3},{:.3},{}",
        cell.time_ns() as f64 * 1e-9,
        cell.mode().name(),
        s.ee[0],
        s.ee[1],
        s.ee[2],
        x_d[0],
        x_d[1],
        x_d[2],
        s.waypoints_reached,
        d,
        part,
        link,
        s.min_distance,
        s.risk,
        s.task_scale,
        collab
    )
}

/// Write the header, then `row` of the cell every time [`Trace::sample`] is due.
pub struct Trace<W: Write> {
    out: W,
    every_ns: u64,
    next_ns: u64,
}

impl<W: Write> Trace<W> {
    /// A trace into `out`, one row every `every_ns` of robot time.
    pub fn new(mut out: W, every_ns: u64) -> std::io::Result<Trace<W>> {
        writeln!(out, "{HEADER}")?;
        Ok(Trace {
            out,
            every_ns: every_ns.max(1),
            next_ns: every_ns.max(1),
        })
    }

    /// After a tick: a row when one is due.
    pub fn sample(&mut self, cell: &Cell) -> std::io::Result<()> {
        if cell.time_ns() >= self.next_ns {
            writeln!(self.out, "{}", row(cell))?;
            self.next_ns += self.every_ns;
        }
        Ok(())
    }

    /// Flush what is buffered.
    pub fn finish(mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}
