//! Spatial (6D) vectors in Plücker coordinates, expressed in the base frame and
//! taken about the base-frame origin (Featherstone's notation).
//!
//! A [`Motion`] is `(ω, v_O)`: angular velocity [rad/s] and the linear velocity
//! [m/s] of the body point that momentarily coincides with the origin. A
//! [`Force`] is `(n_O, f)`: moment about the origin \[Nm\] and force \[N\].

use nalgebra::{Matrix3, Matrix6, Vector3};

/// Spatial motion vector (velocity, acceleration or motion subspace), base frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Motion {
    /// angular part [rad/s or rad/s²], base-frame axes
    pub w: Vector3<f64>,
    /// linear part at the base origin [m/s or m/s²], base-frame axes
    pub v: Vector3<f64>,
}

/// Spatial force vector (wrench or momentum), base frame, about the base origin.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Force {
    /// moment about the base origin \[Nm\]
    pub n: Vector3<f64>,
    /// force \[N\]
    pub f: Vector3<f64>,
}

impl Motion {
    /// no motion
    pub const ZERO: Motion = Motion {
        w: Vector3::new(0.0, 0.0, 0.0),
        v: Vector3::new(0.0, 0.0, 0.0),
    };

    /// From its angular part `w` and its linear part `v` at the base origin.
    #[inline]
    pub fn new(w: Vector3<f64>, v: Vector3<f64>) -> Self {
        Self { w, v }
    }

    /// Both parts times `s`.
    #[inline]
    pub fn scale(&self, s: f64) -> Motion {
        Motion {
            w: self.w * s,
            v: self.v * s,
        }
    }

    /// Motion cross motion: `self × m`.
    #[inline]
    pub fn cross_motion(&self, m: &Motion) -> Motion {
        Motion {
            w: self.w.cross(&m.w),
            v: self.w.cross(&m.v) + self.v.cross(&m.w),
        }
    }

    /// Motion cross force: `self ×* f`.
    #[inline]
    pub fn cross_force(&self, f: &Force) -> Force {
        Force {
            n: self.w.cross(&f.n) + self.v.cross(&f.f),
            f: self.w.cross(&f.f),
        }
    }

    /// Power pairing `selfᵀ f` (motion · force).
    #[inline]
    pub fn dot(&self, f: &Force) -> f64 {
        self.w.dot(&f.n) + self.v.dot(&f.f)
    }

    /// Linear velocity of the base-frame point `p` [m/s].
    #[inline]
    pub fn velocity_at(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.v + self.w.cross(p)
    }

    /// As a 6-vector, ordering (angular, linear).
    #[inline]
    pub fn to_vector(&self) -> nalgebra::Vector6<f64> {
        nalgebra::Vector6::new(self.w.x, self.w.y, self.w.z, self.v.x, self.v.y, self.v.z)
    }
}

impl std::ops::Add for Motion {
    type Output = Motion;
    #[inline]
    fn add(self, o: Motion) -> Motion {
        Motion {
            w: self.w + o.w,
            v: self.v + o.v,
        }
    }
}

impl Force {
    /// no force
    pub const ZERO: Force = Force {
        n: Vector3::new(0.0, 0.0, 0.0),
        f: Vector3::new(0.0, 0.0, 0.0),
    };

    /// From a 6-vector, ordering (moment, force).
    #[inline]
    pub fn from_vector(x: &nalgebra::Vector6<f64>) -> Self {
        Force {
            n: Vector3::new(x[0], x[1], x[2]),
            f: Vector3::new(x[3], x[4], x[5]),
        }
    }
}

impl std::ops::Add for Force {
    type Output = Force;
    #[inline]
    fn add(self, o: Force) -> Force {
        Force {
            n: self.n + o.n,
            f: self.f + o.f,
        }
    }
}

impl std::ops::AddAssign for Force {
    #[inline]
    fn add_assign(&mut self, o: Force) {
        self.n += o.n;
        self.f += o.f;
    }
}

/// Skew-symmetric cross-product matrix `[x]×`.
#[inline]
pub fn skew(x: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -x.z, x.y, x.z, 0.0, -x.x, -x.y, x.x, 0.0)
}

/// Spatial inertia about the base origin, base-frame axes, stored compactly:
/// mass `m` \[kg\], first moment `h = m c` [kg m] and rotational inertia about
/// the origin `I_O = I_c − m [c]×²` [kg m²].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Inertia {
    /// mass \[kg\]
    pub m: f64,
    /// first mass moment `m c` [kg m], base frame
    pub h: Vector3<f64>,
    /// rotational inertia about the base origin [kg m²], base frame
    pub i: Matrix3<f64>,
}

impl Inertia {
    /// no mass, no inertia
    pub const ZERO: Inertia = Inertia {
        m: 0.0,
        h: Vector3::new(0.0, 0.0, 0.0),
        i: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    /// From mass, centre of mass `c` and rotational inertia about the centre of
    /// mass `i_c`, all in base-frame coordinates.
    #[inline]
    pub fn from_com(m: f64, c: &Vector3<f64>, i_c: &Matrix3<f64>) -> Self {
        let cc = skew(c);
        Inertia {
            m,
            h: c * m,
            i: i_c - cc * cc * m,
        }
    }

    /// `I · m` (momentum of a body moving with `m`).
    #[inline]
    pub fn apply(&self, x: &Motion) -> Force {
        Force {
            n: self.i * x.w + self.h.cross(&x.v),
            f: x.v * self.m - self.h.cross(&x.w),
        }
    }

    /// The 6×6 matrix, ordering (angular, linear).
    pub fn to_matrix(&self) -> Matrix6<f64> {
        let mut out = Matrix6::zeros();
        let hx = skew(&self.h);
        out.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.i);
        out.fixed_view_mut::<3, 3>(0, 3).copy_from(&hx);
        out.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-hx));
        out.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() * self.m));
        out
    }

    /// Centre of mass \[m\], base frame (origin for a massless body).
    #[inline]
    pub fn com(&self) -> Vector3<f64> {
        if self.m > 0.0 {
            self.h / self.m
        } else {
            Vector3::zeros()
        }
    }
}

impl std::ops::AddAssign for Inertia {
    #[inline]
    fn add_assign(&mut self, o: Inertia) {
        self.m += o.m;
        self.h += o.h;
        self.i += o.i;
    }
}

/// Matrix of `x ×` acting on motions (6×6, ordering angular, linear).
pub fn crm(x: &Motion) -> Matrix6<f64> {
    let mut out = Matrix6::zeros();
    let wx = skew(&x.w);
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&wx);
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&skew(&x.v));
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&wx);
    out
}

/// Matrix of `x ×*` acting on forces: `−crm(x)ᵀ`.
pub fn crf(x: &Motion) -> Matrix6<f64> {
    -crm(x).transpose()
}

/// Matrix `f ×̄*` with `(f ×̄*) x = x ×* f` for every motion `x` (skew-symmetric).
pub fn icrf(f: &Force) -> Matrix6<f64> {
    let mut out = Matrix6::zeros();
    let nx = -skew(&f.n);
    let fx = -skew(&f.f);
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&nx);
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&fx);
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&fx);
    out
}

/// Rotation from URDF roll-pitch-yaw: `Rz(yaw) Ry(pitch) Rx(roll)`.
pub fn rpy_to_matrix(r: f64, p: f64, y: f64) -> Matrix3<f64> {
    let (sr, cr) = r.sin_cos();
    let (sp, cp) = p.sin_cos();
    let (sy, cy) = y.sin_cos();
    Matrix3::new(
        cy * cp,
        cy * sp * sr - sy * cr,
        cy * sp * cr + sy * sr,
        sy * cp,
        sy * sp * sr + cy * cr,
        sy * sp * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    )
}

/// Rotation by `angle` \[rad\] about the unit axis `u` (Rodrigues).
#[inline]
pub fn axis_angle(u: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    let (x, y, z) = (u.x, u.y, u.z);
    Matrix3::new(
        t * x * x + c,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        t * y * y + c,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        t * z * z + c,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icrf_is_skew_and_matches_cross_force() {
        let f = Force {
            n: Vector3::new(0.3, -1.0, 2.0),
            f: Vector3::new(-0.5, 0.7, 1.1),
        };
        let x = Motion::new(Vector3::new(0.1, 0.2, -0.3), Vector3::new(1.0, -2.0, 0.5));
        let m = icrf(&f);
        assert!((m + m.transpose()).norm() < 1e-15);
        let lhs = m * x.to_vector();
        let rhs = x.cross_force(&f);
        assert!(
            (lhs - nalgebra::Vector6::new(rhs.n.x, rhs.n.y, rhs.n.z, rhs.f.x, rhs.f.y, rhs.f.z))
                .norm()
                < 1e-14
        );
    }

    #[test]
    fn inertia_matrix_matches_apply() {
        let i = Inertia::from_com(
            2.0,
            &Vector3::new(0.1, -0.2, 0.3),
            &Matrix3::new(0.1, 0.01, 0.0, 0.01, 0.2, 0.02, 0.0, 0.02, 0.3),
        );
        let x = Motion::new(Vector3::new(0.4, 0.2, -0.3), Vector3::new(1.0, 0.0, 0.5));
        let a = i.apply(&x);
        let b = i.to_matrix() * x.to_vector();
        assert!(
            (nalgebra::Vector6::new(a.n.x, a.n.y, a.n.z, a.f.x, a.f.y, a.f.z) - b).norm() < 1e-14
        );
        assert!((i.to_matrix() - i.to_matrix().transpose()).norm() < 1e-15);
    }

    #[test]
    fn rodrigues_matches_rpy_about_principal_axes() {
        let a = 0.7;
        assert!((axis_angle(&Vector3::z(), a) - rpy_to_matrix(0.0, 0.0, a)).norm() < 1e-15);
        assert!((axis_angle(&Vector3::y(), a) - rpy_to_matrix(0.0, a, 0.0)).norm() < 1e-15);
        assert!((axis_angle(&Vector3::x(), a) - rpy_to_matrix(a, 0.0, 0.0)).norm() < 1e-15);
    }
}
