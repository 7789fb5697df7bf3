//! The simulated person's contact forces, sent to an arm simulated outside
//! the cell (`sim.forces_to`: franka-sim behind
//! `deploy/franka-sim/serve.py --forces-port`), so that in the hybrid cell
//! the person pushes the outside arm and its own physics answers.
//!
//! One UDP datagram per period while there are contacts (and one empty one
//! when they end): `PHRF`, a little-endian `u32` count, then per contact
//! the touched link's URDF name (32 bytes, UTF-8, zero padded), the
//! application point \[m\] and the force on the robot \[N\], both base
//! frame, as little-endian `f64`. The receiver clears the forces when none
//! arrive for 50 ms. Encoding allocates nothing.

use phri_model::Model;

use crate::sim::{ContactTruth, MAX_CONTACTS};

/// First bytes of every datagram.
pub const MAGIC: &[u8; 4] = b"PHRF";
/// Bytes of a link name.
pub const NAME_BYTES: usize = 32;
/// Bytes of one contact: name, point, force.
pub const RECORD_BYTES: usize = NAME_BYTES + 6 * 8;
/// Largest datagram \[bytes\].
pub const MAX_BYTES: usize = 8 + MAX_CONTACTS * RECORD_BYTES;

/// A datagram of contact forces, preallocated.
pub struct ForcesDatagram {
    buf: [u8; MAX_BYTES],
    /// contacts in the last datagram encoded
    last: usize,
}

impl Default for ForcesDatagram {
    fn default() -> Self {
        ForcesDatagram {
            buf: [0; MAX_BYTES],
            last: 0,
        }
    }
}

impl ForcesDatagram {
    /// The datagram for `contacts` (links named by `model`), or `None` when
    /// there is nothing to say: no contacts now and none in the last one.
    /// A link name longer than [`NAME_BYTES`] is cut (URDF names rarely are).
    pub fn encode(&mut self, model: &Model, contacts: &[ContactTruth]) -> Option<&[u8]> {
        let n = contacts.len().min(MAX_CONTACTS);
        if n == 0 && self.last == 0 {
            return None;
        }
        self.last = n;
        self.buf[..4].copy_from_slice(MAGIC);
        self.buf[4..8].copy_from_slice(&(n as u32).to_le_bytes());
        for (k, c) in contacts.iter().take(n).enumerate() {
            let rec = &mut self.buf[8 + k * RECORD_BYTES..8 + (k + 1) * RECORD_BYTES];
            let name = c.link(model).as_bytes();
            let cut = name.len().min(NAME_BYTES);
            rec[..NAME_BYTES].fill(0);
            rec[..cut].copy_from_slice(&name[..cut]);
            let values = [
                c.point.x, c.point.y, c.point.z, c.force.x, c.force.y, c.force.z,
            ];
            for (i, v) in values.iter().enumerate() {
                let at = NAME_BYTES + 8 * i;
                rec[at..at + 8].copy_from_slice(&v.to_le_bytes());
            }
        }
        Some(&self.buf[..8 + n * RECORD_BYTES])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn model() -> Model {
        let urdf = include_str!("../../../deploy/robots/kuka_lwr4.urdf");
        Model::from_urdf_str(urdf).expect("the LWR's URDF")
    }

    fn contact(model: &Model, link: &str, point: [f64; 3], force: [f64; 3]) -> ContactTruth {
        let collision = model
            .collisions
            .iter()
            .position(|c| c.link == link)
            .expect("a collision object on the link");
        ContactTruth {
            collision,
            part: phri_ipc::BodyPart::HandRight,
            intended: false,
            force: Vector3::from(force),
            point: Vector3::from(point),
            depth: 0.01,
        }
    }

    fn f64_at(b: &[u8], at: usize) -> f64 {
        f64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
    }

    #[test]
    fn a_contact_goes_out_with_its_link_point_and_force_then_one_empty_datagram() {
        let m = model();
        let link = m.collisions[3].link.clone();
        let mut d = ForcesDatagram::default();
        assert!(
            d.encode(&m, &[]).is_none(),
            "nothing to say before a contact"
        );
        let c = contact(&m, &link, [0.4, -0.1, 0.5], [-12.0, 3.0, 0.5]);
        let b = d.encode(&m, &[c]).expect("a datagram").to_vec();
        assert_eq!(b.len(), 8 + RECORD_BYTES);
        assert_eq!(&b[..4], MAGIC);
        assert_eq!(u32::from_le_bytes(b[4..8].try_into().unwrap()), 1);
        let name = &b[8..8 + NAME_BYTES];
        let end = name.iter().position(|&x| x == 0).unwrap_or(NAME_BYTES);
        assert_eq!(std::str::from_utf8(&name[..end]).unwrap(), link);
        let got: Vec<f64> = (0..6).map(|i| f64_at(&b, 8 + NAME_BYTES + 8 * i)).collect();
        assert_eq!(got, vec![0.4, -0.1, 0.5, -12.0, 3.0, 0.5]);
        // the end of the contacts is said once
        let end = d.encode(&m, &[]).expect("the empty datagram").to_vec();
        assert_eq!(end.len(), 8);
        assert_eq!(u32::from_le_bytes(end[4..8].try_into().unwrap()), 0);
        assert!(d.encode(&m, &[]).is_none());
    }

    #[test]
    fn more_contacts_than_a_datagram_holds_are_cut_to_the_deepest_kept() {
        let m = model();
        let link = m.collisions[2].link.clone();
        let many: Vec<ContactTruth> = (0..MAX_CONTACTS + 3)
            .map(|k| contact(&m, &link, [0.0, 0.0, k as f64], [1.0, 0.0, 0.0]))
            .collect();
        let mut d = ForcesDatagram::default();
        let b = d.encode(&m, &many).expect("a datagram");
        assert_eq!(b.len(), MAX_BYTES);
    }
}
