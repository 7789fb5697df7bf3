//! Mass and inertia: each link's `<inertial>` checked and moved into its
//! body's frame, summed per body, and the check that every joint moves some.

use nalgebra::{Matrix3, Vector3};

use super::checked::{finite, pose};
use crate::error::ModelError;
use crate::model::{Joint, JointKind, Placement};

/// Mass properties accumulated in a body frame.
#[derive(Clone, Copy)]
pub(super) struct MassProps {
    /// [kg]
    pub m: f64,
    /// Σ m c [kg m]
    h: Vector3<f64>,
    /// Σ (I_c + m (|c|² 1 − c cᵀ)), about the body origin [kg m²]
    i_o: Matrix3<f64>,
}

impl MassProps {
    pub const ZERO: MassProps = MassProps {
        m: 0.0,
        h: Vector3::new(0.0, 0.0, 0.0),
        i_o: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    /// Adds a mass `m` [kg] centred at `c` [m] with inertia `i_c` about it
    /// [kg m²], all in the body frame.
    pub fn add(&mut self, m: f64, c: &Vector3<f64>, i_c: &Matrix3<f64>) {
        self.m += m;
        self.h += c * m;
        self.i_o += i_c + (Matrix3::identity() * c.norm_squared() - c * c.transpose()) * m;
    }

    /// (mass, com, inertia about com)
    pub fn split(&self) -> (f64, Vector3<f64>, Matrix3<f64>) {
        if self.m <= 0.0 {
            return (0.0, Vector3::zeros(), Matrix3::zeros());
        }
        let c = self.h / self.m;
        let i_c = self.i_o - (Matrix3::identity() * c.norm_squared() - c * c.transpose()) * self.m;
        (self.m, c, i_c)
    }
}

/// A link's mass \[kg\], centre of mass \[m\] and inertia about it
/// \[kg m²\], body frame.
type Inertial = (f64, Vector3<f64>, Matrix3<f64>);

/// The `<inertial>` of `link`, whose frame sits at `in_body` in its body's
/// frame: mass [kg], centre of mass [m] and inertia about it [kg m²], body
/// frame; `None` without mass and inertia. Refuses a negative mass, a
/// number that is not finite, an inertia that is not positive semidefinite.
pub(super) fn link_inertial(
    link: &urdf_rs::Link,
    in_body: &Placement,
) -> Result<Option<Inertial>, ModelError> {
    let inertial = &link.inertial;
    let el = format!("link '{}' inertial", link.name);
    let m = finite(inertial.mass.value, &el, "mass")?;
    if m < 0.0 {
        return Err(ModelError::Inertia {
            link: link.name.clone(),
            reason: format!("negative mass {m}"),
        });
    }
    let it = &inertial.inertia;
    let vals = [it.ixx, it.ixy, it.ixz, it.iyy, it.iyz, it.izz];
    if vals.iter().any(|v| !v.is_finite()) {
        return Err(ModelError::NotFinite {
            element: el,
            field: "inertia".into(),
        });
    }
    let i_local = Matrix3::new(
        it.ixx, it.ixy, it.ixz, it.ixy, it.iyy, it.iyz, it.ixz, it.iyz, it.izz,
    );
    if !(m > 0.0 || i_local.norm() > 0.0) {
        return Ok(None);
    }
    let eig = i_local.symmetric_eigenvalues();
    if eig.iter().any(|&e| e < -1e-12) {
        return Err(ModelError::Inertia {
            link: link.name.clone(),
            reason: "rotational inertia is not positive semidefinite".into(),
        });
    }
    let io = in_body.compose(&pose(&inertial.origin, &el)?);
    Ok(Some((m, io.p, io.r * i_local * io.r.transpose())))
}

/// Every joint must move some mass, whatever the configuration: a prismatic
/// joint some mass in its subtree, a revolute one some mass or rotational
/// inertia (a body keeps inertia only with mass: [`MassProps::split`]). Otherwise its column of `M` is zero at every `q` (singular `M`:
/// forward dynamics, the residual and the controller's inverse fail).
/// Configuration-dependent singularities (mass only on the axis) are the
/// configuration's check (`phri-config`, at the start posture). An actuated
/// joint moves its own subtree and those of its mimic joints whose multiplier
/// is not zero; the deepest joint that moves nothing is named.
pub(super) fn moves_mass(joints: &[Joint], order: &[usize], nv: usize) -> Result<(), ModelError> {
    let mut mass: Vec<f64> = joints.iter().map(|j| j.mass).collect();
    let mut inertia: Vec<f64> = joints.iter().map(|j| j.inertia_com.trace()).collect();
    for &i in order.iter().rev() {
        if let Some(p) = joints[i].parent {
            mass[p] += mass[i];
            inertia[p] += inertia[i];
        }
    }
    let mut moves = vec![false; nv];
    for (i, j) in joints.iter().enumerate() {
        let scale = j.mimic.map_or(1.0, |m| m.multiplier);
        let subtree = match j.kind {
            JointKind::Prismatic => mass[i] > 0.0,
            JointKind::Revolute => mass[i] > 0.0 || inertia[i] > 0.0,
        };
        moves[j.idx_v] |= scale != 0.0 && subtree;
    }
    match moves.iter().rposition(|&m| !m) {
        Some(i) => Err(ModelError::MovesNoMass {
            joint: joints[i].name.clone(),
        }),
        None => Ok(()),
    }
}
