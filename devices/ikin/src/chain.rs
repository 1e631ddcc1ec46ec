//! A serial chain of revolute links with blocking/releasing, as iKin's `iKinChain`.

use nalgebra::{DVector, Matrix3, Matrix4, Matrix6xX, Vector3, Vector6};

use crate::error::{KinError, Result};
use crate::link::{Link, DEG2RAD, RAD2DEG};
use crate::pose::{self, Vector7};

/// A kinematic chain: `H = H0 · H_0(q_0) · … · H_{N-1}(q_{N-1}) · HN`.
///
/// Like `iKinChain`, each link has a current angle; *blocked* links keep
/// theirs fixed and are excluded from the degrees of freedom (DOF), so joint
/// vectors passed to [`Chain::set_ang`] and returned Jacobian columns cover
/// the released links only, in chain order. When the chain is *constrained*
/// (default) every angle set through the chain is clamped to its bounds.
/// A new link starts at its lower bound, as in iKin.
#[derive(Debug, Clone, PartialEq)]
pub struct Chain {
    links: Vec<Link>,
    angles: Vec<f64>,
    blocked: Vec<bool>,
    h0: Matrix4<f64>,
    hn: Matrix4<f64>,
    constrained: bool,
    /// Indices (into `links`) of the released links; rebuilt on every change.
    dof_links: Vec<usize>,
}

impl Default for Chain {
    fn default() -> Self {
        Self::new()
    }
}

impl Chain {
    /// An empty chain with `H0 = HN = I`.
    pub fn new() -> Self {
        Self {
            links: Vec::new(),
            angles: Vec::new(),
            blocked: Vec::new(),
            h0: Matrix4::identity(),
            hn: Matrix4::identity(),
            constrained: true,
            dof_links: Vec::new(),
        }
    }

    /// A chain with the given base transform and links (all released).
    pub fn from_links(h0: Matrix4<f64>, links: impl IntoIterator<Item = Link>) -> Self {
        let mut c = Self::new();
        c.h0 = h0;
        for l in links {
            c.push_link(l);
        }
        c
    }

    fn rebuild(&mut self) {
        self.dof_links = (0..self.links.len())
            .filter(|&i| !self.blocked[i])
            .collect();
    }

    fn check_index(&self, i: usize) -> Result<()> {
        if i < self.links.len() {
            Ok(())
        } else {
            Err(KinError::LinkIndex {
                index: i,
                n: self.links.len(),
            })
        }
    }

    fn bound(&self, i: usize, q: f64) -> f64 {
        if self.constrained {
            self.links[i].clamp(q)
        } else {
            q
        }
    }

    /// Appends a released link (iKin `pushLink`).
    pub fn push_link(&mut self, link: Link) {
        self.links.push(link);
        self.angles.push(link.min);
        self.blocked.push(false);
        self.rebuild();
    }

    /// Inserts a released link before index `i` (iKin `addLink`); `i == n()` appends.
    pub fn insert_link(&mut self, i: usize, link: Link) -> Result<()> {
        if i > self.links.len() {
            return Err(KinError::LinkIndex {
                index: i,
                n: self.links.len(),
            });
        }
        self.links.insert(i, link);
        self.angles.insert(i, link.min);
        self.blocked.insert(i, false);
        self.rebuild();
        Ok(())
    }

    /// Removes link `i` (iKin `rmLink`).
    pub fn remove_link(&mut self, i: usize) -> Result<Link> {
        self.check_index(i)?;
        let l = self.links.remove(i);
        self.angles.remove(i);
        self.blocked.remove(i);
        self.rebuild();
        Ok(l)
    }

    /// Removes the last link (iKin `popLink`).
    pub fn pop_link(&mut self) -> Option<Link> {
        let l = self.links.pop()?;
        self.angles.pop();
        self.blocked.pop();
        self.rebuild();
        Some(l)
    }

    /// Number of links `N`.
    pub fn n(&self) -> usize {
        self.links.len()
    }

    /// Number of released links (DOF).
    pub fn dof(&self) -> usize {
        self.dof_links.len()
    }

    /// Link `i`.
    pub fn link(&self, i: usize) -> Result<&Link> {
        self.check_index(i)?;
        Ok(&self.links[i])
    }

    /// All links, in chain order.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// Replaces the DH parameters of link `i`, keeping its blocked state;
    /// the current angle is re-clamped to the new bounds.
    pub fn set_link(&mut self, i: usize, link: Link) -> Result<()> {
        self.check_index(i)?;
        if link.min > link.max {
            return Err(KinError::InvalidBounds {
                min: link.min,
                max: link.max,
            });
        }
        self.links[i] = link;
        self.angles[i] = link.clamp(self.angles[i]);
        Ok(())
    }

    /// Sets the bounds of link `i` \[rad\] (iKin `setMin`/`setMax`): the current angle is clamped.
    pub fn set_limits(&mut self, i: usize, min: f64, max: f64) -> Result<()> {
        let l = *self.link(i)?;
        self.set_link(i, Link { min, max, ..l })
    }

    /// Indices of the released links (iKin's `hash`).
    pub fn dof_links(&self) -> &[usize] {
        &self.dof_links
    }

    /// Lower and upper bounds of the released joints \[rad\].
    pub fn dof_limits(&self) -> (DVector<f64>, DVector<f64>) {
        let lo = self.dof_links.iter().map(|&i| self.links[i].min);
        let hi = self.dof_links.iter().map(|&i| self.links[i].max);
        (
            DVector::from_iterator(self.dof(), lo),
            DVector::from_iterator(self.dof(), hi),
        )
    }

    /// Base transform `H0` (root frame to frame of link 0's joint).
    pub fn h0(&self) -> &Matrix4<f64> {
        &self.h0
    }

    /// End transform `HN` (last link frame to end-effector).
    pub fn hn(&self) -> &Matrix4<f64> {
        &self.hn
    }

    /// Sets `H0`.
    pub fn set_h0(&mut self, h0: Matrix4<f64>) -> Result<()> {
        if !h0.iter().all(|v| v.is_finite()) {
            return Err(KinError::NonFinite("H0"));
        }
        self.h0 = h0;
        Ok(())
    }

    /// Sets `HN`.
    pub fn set_hn(&mut self, hn: Matrix4<f64>) -> Result<()> {
        if !hn.iter().all(|v| v.is_finite()) {
            return Err(KinError::NonFinite("HN"));
        }
        self.hn = hn;
        Ok(())
    }

    /// Whether angles are clamped to the link bounds.
    pub fn is_constrained(&self) -> bool {
        self.constrained
    }

    /// Enables or disables clamping to bounds (iKin `setAllConstraints`).
    pub fn set_constrained(&mut self, on: bool) {
        self.constrained = on;
    }

    /// Blocks link `i` at angle `q` (clamped if constrained); returns the angle set.
    pub fn block_link(&mut self, i: usize, q: f64) -> Result<f64> {
        self.check_index(i)?;
        if !q.is_finite() {
            return Err(KinError::NonFinite("blocking value"));
        }
        self.angles[i] = self.bound(i, q);
        self.blocked[i] = true;
        self.rebuild();
        Ok(self.angles[i])
    }

    /// Changes the angle of an already blocked link (iKin `setBlockingValue`).
    pub fn set_blocking_value(&mut self, i: usize, q: f64) -> Result<f64> {
        self.check_index(i)?;
        if !self.blocked[i] {
            return Err(KinError::NotBlocked(i));
        }
        self.block_link(i, q)
    }

    /// Releases link `i`, adding it to the DOF.
    pub fn release_link(&mut self, i: usize) -> Result<()> {
        self.check_index(i)?;
        self.blocked[i] = false;
        self.rebuild();
        Ok(())
    }

    /// Whether link `i` is blocked.
    pub fn is_blocked(&self, i: usize) -> Result<bool> {
        self.check_index(i)?;
        Ok(self.blocked[i])
    }

    /// Sets the released joints \[rad\] (clamped if constrained) and returns the values set.
    pub fn set_ang(&mut self, q: &[f64]) -> Result<DVector<f64>> {
        self.check_dof(q)?;
        for (k, &i) in self.dof_links.clone().iter().enumerate() {
            self.angles[i] = self.bound(i, q[k]);
        }
        Ok(self.ang())
    }

    /// [`Chain::set_ang`] with values in degrees; returns degrees.
    pub fn set_ang_deg(&mut self, q_deg: &[f64]) -> Result<DVector<f64>> {
        let q: Vec<f64> = q_deg.iter().map(|v| v * DEG2RAD).collect();
        Ok(self.set_ang(&q)? * RAD2DEG)
    }

    /// Current released joint values \[rad\].
    pub fn ang(&self) -> DVector<f64> {
        DVector::from_iterator(self.dof(), self.dof_links.iter().map(|&i| self.angles[i]))
    }

    /// Current released joint values \[deg\].
    pub fn ang_deg(&self) -> DVector<f64> {
        self.ang() * RAD2DEG
    }

    /// Sets the angle of link `i` whether blocked or not (iKin `setAng(i, q)`).
    pub fn set_link_ang(&mut self, i: usize, q: f64) -> Result<f64> {
        self.check_index(i)?;
        if !q.is_finite() {
            return Err(KinError::NonFinite("joint angle"));
        }
        self.angles[i] = self.bound(i, q);
        Ok(self.angles[i])
    }

    /// Angle of link `i` \[rad\].
    pub fn link_ang(&self, i: usize) -> Result<f64> {
        self.check_index(i)?;
        Ok(self.angles[i])
    }

    /// Angles of all links, blocked ones included \[rad\].
    pub fn all_angles(&self) -> &[f64] {
        &self.angles
    }

    fn check_dof(&self, q: &[f64]) -> Result<()> {
        if self.dof() == 0 {
            return Err(KinError::NoDof);
        }
        if q.len() != self.dof() {
            return Err(KinError::DimensionMismatch {
                expected: self.dof(),
                got: q.len(),
            });
        }
        if !q.iter().all(|v| v.is_finite()) {
            return Err(KinError::NonFinite("joint vector"));
        }
        Ok(())
    }

    /// All link angles with the released ones replaced by `q` (not clamped).
    fn angles_with(&self, q: &[f64]) -> Result<Vec<f64>> {
        self.check_dof(q)?;
        let mut a = self.angles.clone();
        for (k, &i) in self.dof_links.iter().enumerate() {
            a[i] = q[k];
        }
        Ok(a)
    }

    fn fk_angles(&self, angles: impl IntoIterator<Item = f64>) -> Matrix4<f64> {
        let mut h = self.h0;
        for (l, q) in self.links.iter().zip(angles) {
            h *= l.h(q);
        }
        h * self.hn
    }

    /// All link angles with the released ones taken from `q`, without
    /// allocating (the forward kinematics hot path of the IK loop).
    fn merged<'a>(&'a self, q: &'a [f64]) -> Result<impl Iterator<Item = f64> + 'a> {
        self.check_dof(q)?;
        let mut next = q.iter().copied();
        Ok(self
            .angles
            .iter()
            .zip(&self.blocked)
            .map(move |(&a, &blocked)| if blocked { a } else { next.next().unwrap_or(a) }))
    }

    /// Prefix transforms `T_0 = H0, T_{k+1} = T_k · H_k`, length `N + 1`.
    fn prefixes(&self, angles: &[f64]) -> Vec<Matrix4<f64>> {
        let mut t = Vec::with_capacity(self.links.len() + 1);
        t.push(self.h0);
        for (k, (l, &q)) in self.links.iter().zip(angles).enumerate() {
            let next = t[k] * l.h(q);
            t.push(next);
        }
        t
    }

    fn geo_jacobian_angles(&self, angles: &[f64]) -> Matrix6xX<f64> {
        let t = self.prefixes(angles);
        let pn = translation(&(t[self.links.len()] * self.hn));
        let mut j = Matrix6xX::zeros(self.dof());
        for (col, &i) in self.dof_links.iter().enumerate() {
            j.set_column(col, &geo_column(&t[i], &pn));
        }
        j
    }

    fn ana_jacobian_angles(&self, angles: &[f64]) -> Matrix6xX<f64> {
        let n = self.links.len();
        let t = self.prefixes(angles);
        // suffix[k] = H_k · … · H_{N-1} · HN
        let mut suffix = vec![self.hn; n + 1];
        for k in (0..n).rev() {
            suffix[k] = self.links[k].h(angles[k]) * suffix[k + 1];
        }
        let h = t[n] * self.hn;
        let r = pose::rotation(&h);
        let mut j = Matrix6xX::zeros(self.dof());
        for (col, &i) in self.dof_links.iter().enumerate() {
            let dh = t[i] * self.links[i].dh(angles[i]) * suffix[i + 1];
            let dr = d_rot(&dh);
            let e = pose::d_rot_ang(&r, &dr);
            j.column_mut(col).copy_from(&Vector6::new(
                dh[(0, 3)],
                dh[(1, 3)],
                dh[(2, 3)],
                e.x,
                e.y,
                e.z,
            ));
        }
        j
    }

    /// End-effector transform at the current angles (iKin `getH()`).
    pub fn h(&self) -> Matrix4<f64> {
        self.fk_angles(self.angles.iter().copied())
    }

    /// End-effector transform at released joints `q` \[rad\], without
    /// changing the chain and without clamping.
    pub fn h_at(&self, q: &[f64]) -> Result<Matrix4<f64>> {
        Ok(self.fk_angles(self.merged(q)?))
    }

    /// Frame of link `i` counting all links, blocked ones included; for the
    /// last link `HN` is appended (iKin `getH(i, true)`).
    pub fn link_h(&self, i: usize) -> Result<Matrix4<f64>> {
        self.check_index(i)?;
        let mut h = self.h0;
        for k in 0..=i {
            h *= self.links[k].h(self.angles[k]);
        }
        if i + 1 == self.links.len() {
            h *= self.hn;
        }
        Ok(h)
    }

    /// Origin of link `i`'s frame (iKin `Position(i)`).
    pub fn link_position(&self, i: usize) -> Result<Vector3<f64>> {
        Ok(translation(&self.link_h(i)?))
    }

    /// End-effector pose as iKin's 7-vector `x y z ax ay az θ` (`EndEffPose()`).
    pub fn end_eff_pose(&self) -> Vector7<f64> {
        pose::pose7(&self.h())
    }

    /// End-effector pose as `x y z` plus XYZ Euler angles (`EndEffPose(false)`).
    pub fn end_eff_pose_euler(&self) -> Vector6<f64> {
        pose::pose6(&self.h())
    }

    /// End-effector position \[m\].
    pub fn end_eff_position(&self) -> Vector3<f64> {
        translation(&self.h())
    }

    /// 7-vector pose at released joints `q` \[rad\] (chain unchanged).
    pub fn pose_at(&self, q: &[f64]) -> Result<Vector7<f64>> {
        Ok(pose::pose7(&self.h_at(q)?))
    }

    /// Geometric Jacobian (6 × DOF) at the current angles: rows are linear
    /// velocity then angular velocity of the end-effector in the root frame
    /// (iKin `GeoJacobian()`).
    pub fn geo_jacobian(&self) -> Matrix6xX<f64> {
        self.geo_jacobian_angles(&self.angles)
    }

    /// [`Chain::geo_jacobian`] at released joints `q` \[rad\].
    pub fn geo_jacobian_at(&self, q: &[f64]) -> Result<Matrix6xX<f64>> {
        Ok(self.geo_jacobian_angles(&self.angles_with(q)?))
    }

    /// Geometric Jacobian of the frame of link `i` w.r.t. links `0..=i`,
    /// blocked ones included (iKin `GeoJacobian(i)`), 6 × (i + 1).
    pub fn link_geo_jacobian(&self, i: usize) -> Result<Matrix6xX<f64>> {
        self.check_index(i)?;
        let t = self.prefixes(&self.angles);
        let pn = translation(&self.link_h(i)?);
        let mut j = Matrix6xX::zeros(i + 1);
        for (k, tk) in t.iter().take(i + 1).enumerate() {
            j.set_column(k, &geo_column(tk, &pn));
        }
        Ok(j)
    }

    /// Analytical Jacobian (6 × DOF): derivative of [`Chain::end_eff_pose_euler`]
    /// (position and XYZ Euler angles) w.r.t. the released joints (iKin `AnaJacobian()`).
    pub fn ana_jacobian(&self) -> Matrix6xX<f64> {
        self.ana_jacobian_angles(&self.angles)
    }

    /// [`Chain::ana_jacobian`] at released joints `q` \[rad\].
    pub fn ana_jacobian_at(&self, q: &[f64]) -> Result<Matrix6xX<f64>> {
        Ok(self.ana_jacobian_angles(&self.angles_with(q)?))
    }

    /// Geometric Jacobian with columns per degree (for joint rates in deg/s).
    pub fn geo_jacobian_deg(&self) -> Matrix6xX<f64> {
        self.geo_jacobian() * DEG2RAD
    }
}

fn translation(h: &Matrix4<f64>) -> Vector3<f64> {
    pose::translation(h)
}

/// Jacobian column of a revolute joint whose frame is `t` for an end point
/// `pn`: `[z × (pn − p); z]`, z being the joint axis (the frame's z axis).
fn geo_column(t: &Matrix4<f64>, pn: &Vector3<f64>) -> Vector6<f64> {
    let z = Vector3::new(t[(0, 2)], t[(1, 2)], t[(2, 2)]);
    let v = z.cross(&(pn - translation(t)));
    Vector6::new(v.x, v.y, v.z, z.x, z.y, z.z)
}

fn d_rot(dh: &Matrix4<f64>) -> Matrix3<f64> {
    dh.fixed_view::<3, 3>(0, 0).into_owned()
}
