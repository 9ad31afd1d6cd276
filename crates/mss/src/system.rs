//! The mass–spring system and its step, in the thesis's phase order.

use glam::{Vec3, Vec3A};

use crate::layout::{AnchorRecord, Layout};
use crate::spring::{spring_force, Anchor, Spring};
use crate::{MssError, Particles, VolumePreservation, VolumePressure};

/// How velocities and positions advance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Integrator {
    /// The thesis's explicit Euler, eqs. (6)–(7): `v ← v + f/m·h`, `x ← x + v_old·h` (the
    /// position uses the velocity from before the update). Adds energy `1 + (ωh)²` per step to
    /// an undamped oscillator of angular frequency `ω`: it needs damping.
    #[default]
    ExplicitEuler,
    /// Semi-implicit (symplectic) Euler: `v ← v + f/m·h`, `x ← x + v_new·h`. Energy stays bounded
    /// for `ωh < 2`.
    SymplecticEuler,
}

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// The step's number (0-based).
    pub step: u64,
    /// The time step used (s).
    pub h: f32,
    /// `Σᵢ |Δxᵢ|`: the summed displacement of the step, the thesis's stop measure (cm).
    pub displacement: f64,
    /// The largest single displacement of the step (cm).
    pub max_move: f32,
}

/// Partial sums of one block of the position update, combined in block order.
#[derive(Debug, Clone, Copy, PartialEq)]
struct BlockSums {
    displacement: f64,
    max_move_sq: f32,
    /// First particle found non-finite, or `u32::MAX`.
    bad: u32,
}

impl BlockSums {
    const EMPTY: BlockSums = BlockSums {
        displacement: 0.0,
        max_move_sq: 0.0,
        bad: u32::MAX,
    };
}

/// A mass–spring system: particles, springs, anchors, volume preservation, external forces,
/// damping and an integrator.
///
/// ## Step, in the thesis's order (SPEC A.2)
/// 1. **forces** ([`MassSpringSystem::compute_forces`]): gravity `mᵢg`, the external field,
///    anchors `k(target − x)`, springs (eq. 4), volume preservation (eq. 5);
/// 2. **velocities** ([`MassSpringSystem::update_velocities`]): `v ← (v + f/m·h)·damping` for free
///    particles;
/// 3. **collisions**: the caller's, on [`Particles::velocities_mut`] (see
///    [`MassSpringSystem::step_with`]);
/// 4. **positions** ([`MassSpringSystem::update_positions`]): `x ← x + v·h` (`v_old` for explicit
///    Euler), summing the displacement;
/// 5. **stop check**: the caller's, e.g. [`crate::SettleDetector`] in [`MassSpringSystem::run`].
///
/// [`MassSpringSystem::step`] runs 1, 2 and 4 fused in one sweep over the particles.
///
/// Fixed particles (inverse mass 0) are not moved by forces; they keep whatever velocity they
/// were given (zero unless set), so a fixed particle with a velocity moves kinematically.
///
/// Nothing allocates inside a step: scratch space is created with the system.
#[derive(Debug, Clone)]
pub struct MassSpringSystem {
    particles: Particles,
    springs: Vec<Spring>,
    anchors: Vec<AnchorRecord>,
    volumes: Vec<VolumePreservation>,
    pressures: Vec<VolumePressure>,
    external: Vec<Vec3A>,
    gravity: Vec3A,
    damping: f32,
    integrator: Integrator,
    parallel: bool,
    step: u64,
    layout: Layout,
    min_rest: f32,
    // Scratch.
    previous_velocity: Vec<Vec3A>,
    block_sums: Vec<BlockSums>,
    volume_scratch: Vec<f32>,
}

impl MassSpringSystem {
    /// A system of `particles` joined by `springs` (validated: indices in range, no self-spring,
    /// finite rest ≥ 0 and stiffness ≥ 0). No gravity, no damping, explicit Euler, parallel when
    /// the `parallel` feature is on and the system is large enough.
    pub fn new(particles: Particles, springs: Vec<Spring>) -> Result<Self, MssError> {
        let n = particles.len();
        for (i, s) in springs.iter().enumerate() {
            s.check(i, n)?;
        }
        let mut system = MassSpringSystem {
            previous_velocity: vec![Vec3A::ZERO; n],
            particles,
            springs,
            anchors: Vec::new(),
            volumes: Vec::new(),
            pressures: Vec::new(),
            external: Vec::new(),
            gravity: Vec3A::ZERO,
            damping: 1.0,
            integrator: Integrator::default(),
            parallel: cfg!(feature = "parallel"),
            step: 0,
            layout: Layout::arrange(0, &mut [], &mut []),
            min_rest: f32::INFINITY,
            block_sums: Vec::new(),
            volume_scratch: Vec::new(),
        };
        system.rearrange();
        Ok(system)
    }

    fn rearrange(&mut self) {
        self.layout = Layout::arrange(self.particles.len(), &mut self.springs, &mut self.anchors);
        self.block_sums = vec![BlockSums::EMPTY; self.layout.count];
        self.min_rest = self
            .springs
            .iter()
            .map(|s| s.rest)
            .filter(|&r| r > 0.0)
            .fold(f32::INFINITY, f32::min);
    }

    /// Adds springs (validated as in [`MassSpringSystem::new`]), e.g. between layers.
    pub fn add_springs(&mut self, springs: &[Spring]) -> Result<(), MssError> {
        let n = self.particles.len();
        let first = self.springs.len();
        for (i, s) in springs.iter().enumerate() {
            s.check(first + i, n)?;
        }
        self.springs.extend_from_slice(springs);
        self.rearrange();
        Ok(())
    }

    /// Adds zero-length springs to fixed points.
    pub fn add_anchors(&mut self, anchors: &[Anchor]) -> Result<(), MssError> {
        let n = self.particles.len();
        for (i, a) in anchors.iter().enumerate() {
            let what = if a.particle as usize >= n {
                Some(format!("particle out of range (the system has {n})"))
            } else if !(a.k.is_finite() && a.k >= 0.0) {
                Some(format!("stiffness {} must be finite and ≥ 0", a.k))
            } else if !a.target.is_finite() {
                Some(format!("target {} is not finite", a.target))
            } else {
                None
            };
            if let Some(what) = what {
                return Err(MssError::InvalidAnchor {
                    anchor: i,
                    particle: a.particle,
                    what,
                });
            }
        }
        self.anchors.extend(anchors.iter().map(|a| AnchorRecord {
            particle: a.particle,
            k: a.k,
            target: Vec3A::from(a.target),
        }));
        self.rearrange();
        Ok(())
    }

    /// Keeps only the anchors whose particle `keep` accepts (the others are removed: the
    /// particle is no longer held to its target).
    pub fn retain_anchors(&mut self, mut keep: impl FnMut(u32) -> bool) {
        self.anchors.retain(|a| keep(a.particle));
        self.rearrange();
    }

    /// The anchors as `(particle, stiffness)` (g/s²), in storage order.
    pub fn anchor_stiffnesses(&self) -> impl Iterator<Item = (u32, f32)> + '_ {
        self.anchors.iter().map(|a| (a.particle, a.k))
    }

    /// The volume preservations (eq. 5) added to the system.
    pub fn volume_preservations(&self) -> &[VolumePreservation] {
        &self.volumes
    }

    /// The fills' pressures added to the system.
    pub fn volume_pressures(&self) -> &[VolumePressure] {
        &self.pressures
    }

    /// The anchors' particles, in storage order.
    pub fn anchored_particles(&self) -> impl Iterator<Item = u32> + '_ {
        self.anchors.iter().map(|a| a.particle)
    }

    /// Adds volume preservation (eq. 5) for one closed object.
    pub fn add_volume_preservation(&mut self, volume: VolumePreservation) -> Result<(), MssError> {
        volume.check(self.particles.len())?;
        self.volume_scratch.reserve(volume.particles.len());
        self.volumes.push(volume);
        Ok(())
    }

    /// The largest stable time step of symplectic Euler for this system (s), or `None` when no
    /// free particle is held by any stiffness.
    ///
    /// A Gershgorin bound on the stiffness: a free particle `i` whose springs and anchors sum to
    /// `Kᵢ` and whose mass is `mᵢ` bounds the squared angular frequencies by
    /// `ω² ≤ 2·max Kᵢ/mᵢ`, and symplectic Euler is stable for `ωh < 2`; so
    /// `h < 2/√(2·max Kᵢ/mᵢ)`. Volume preservation adds `cᵢ·k_v·(C + Σⱼ cⱼ/3)` to `Kᵢ` (the
    /// row sum of its eq. (5) coupling) and a fill's pressure `K/V₀·|∇ᵢV|·Σⱼ|∇ⱼV|`. The bound is exact for two equal masses on one spring,
    /// and conservative otherwise. Damping makes no difference to it.
    pub fn stable_time_step(&self) -> Option<f32> {
        self.stable_time_step_with(&[])
    }

    /// [`MassSpringSystem::stable_time_step`] with `extra` stiffness (g/s²) on some particles:
    /// forces a caller adds to the system's own (each `(particle, k)` adds `k` to the
    /// particle's row sum; out-of-range particles are ignored).
    pub fn stable_time_step_with(&self, extra: &[(u32, f64)]) -> Option<f32> {
        let mut k = vec![0.0f64; self.particles.len()];
        for &(i, x) in extra {
            if let Some(row) = k.get_mut(i as usize) {
                *row += x.abs();
            }
        }
        for s in &self.springs {
            k[s.a as usize] += f64::from(s.k).abs();
            k[s.b as usize] += f64::from(s.k).abs();
        }
        for a in &self.anchors {
            k[a.particle as usize] += f64::from(a.k);
        }
        for v in &self.volumes {
            let coupling: f64 = v.weight.iter().map(|&c| f64::from(c)).sum::<f64>() / 3.0;
            for (&p, &c) in v.particles.iter().zip(&v.weight) {
                k[p as usize] += f64::from(c) * f64::from(v.k_v) * (f64::from(v.c) + coupling);
            }
        }
        for p in &self.pressures {
            for (i, row) in p.row_stiffness() {
                k[i as usize] += row;
            }
        }

        let worst = k
            .iter()
            .zip(&self.particles.inverse_mass)
            .map(|(k, &w)| k * f64::from(w))
            .fold(0.0f64, f64::max);
        (worst > 0.0).then(|| (2.0 / (2.0 * worst).sqrt()) as f32)
    }

    /// Adds the pressure of an enclosed fill ([`VolumePressure`]).
    pub fn add_volume_pressure(&mut self, pressure: VolumePressure) -> Result<(), MssError> {
        pressure.check(self.particles.len())?;
        self.pressures.push(pressure);
        Ok(())
    }

    /// Gravity (cm/s²), e.g. `(0, 0, -981)`.
    pub fn set_gravity(&mut self, g: Vec3) -> Result<(), MssError> {
        if !g.is_finite() {
            return Err(MssError::InvalidParameter {
                name: "gravity",
                value: f64::from(g.length()),
                expected: "finite",
            });
        }
        self.gravity = Vec3A::from(g);
        Ok(())
    }

    /// A constant external force per particle (g·cm/s²); an empty slice removes it.
    pub fn set_external_forces(&mut self, forces: &[Vec3]) -> Result<(), MssError> {
        if forces.is_empty() {
            self.external.clear();
            return Ok(());
        }
        if forces.len() != self.particles.len() {
            return Err(MssError::LengthMismatch {
                what: "external forces",
                got: forces.len(),
                expected: self.particles.len(),
            });
        }
        if let Some(i) = forces.iter().position(|f| !f.is_finite()) {
            return Err(MssError::InvalidParticle {
                particle: i as u32,
                what: format!("external force {} is not finite", forces[i]),
            });
        }
        self.external = forces.iter().map(|&f| Vec3A::from(f)).collect();
        Ok(())
    }

    /// The thesis's damping: after each velocity update, free velocities are multiplied by
    /// `factor` ∈ (0, 1] (1 = none).
    pub fn set_damping(&mut self, factor: f32) -> Result<(), MssError> {
        if !(factor > 0.0 && factor <= 1.0) {
            return Err(MssError::InvalidParameter {
                name: "damping",
                value: f64::from(factor),
                expected: "in (0, 1]",
            });
        }
        self.damping = factor;
        Ok(())
    }

    /// Chooses the integrator.
    pub fn set_integrator(&mut self, integrator: Integrator) {
        self.integrator = integrator;
    }

    /// Turns the parallel path on or off (it only exists with the `parallel` feature). Results
    /// are bit-identical either way.
    pub fn set_parallel(&mut self, parallel: bool) {
        self.parallel = parallel && cfg!(feature = "parallel");
    }

    /// The particles.
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// The particles, to move or fix them between steps.
    pub fn particles_mut(&mut self) -> &mut Particles {
        &mut self.particles
    }

    /// The springs, in the system's internal order (grouped by particle block, sorted by first
    /// particle, each stored with `a < b`; not the order they were given in).
    pub fn springs(&self) -> &[Spring] {
        &self.springs
    }

    /// Sets every spring's rest length to `rest(index, spring)` (index in [`Self::springs`]'
    /// order): a grown or remodelled tissue changes its rest metric between runs, the
    /// particles, stiffnesses and layout stay. Nothing is changed when a value is not finite
    /// or negative ([`MssError::InvalidSpring`] names the spring).
    ///
    /// # Errors
    /// [`MssError::InvalidSpring`].
    pub fn set_rest_lengths(
        &mut self,
        mut rest: impl FnMut(usize, &Spring) -> f32,
    ) -> Result<(), MssError> {
        let mut new = Vec::with_capacity(self.springs.len());
        for (i, s) in self.springs.iter().enumerate() {
            let spring = Spring {
                rest: rest(i, s),
                ..*s
            };
            spring.check(i, self.particles.len())?;
            new.push(spring.rest);
        }
        for (s, r) in self.springs.iter_mut().zip(new) {
            s.rest = r;
        }
        self.min_rest = self
            .springs
            .iter()
            .map(|s| s.rest)
            .filter(|&r| r > 0.0)
            .fold(f32::INFINITY, f32::min);
        Ok(())
    }

    /// Sets every spring's stiffness to `k(index, spring)` (index in [`Self::springs`]' order),
    /// e.g. a material scaled between runs. Nothing is changed when a value is not finite or
    /// negative. The stable time step changes with it: a running integrator keeps its own.
    ///
    /// # Errors
    /// [`MssError::InvalidSpring`].
    pub fn set_stiffnesses(
        &mut self,
        mut k: impl FnMut(usize, &Spring) -> f32,
    ) -> Result<(), MssError> {
        let mut new = Vec::with_capacity(self.springs.len());
        for (i, s) in self.springs.iter().enumerate() {
            let spring = Spring { k: k(i, s), ..*s };
            spring.check(i, self.particles.len())?;
            new.push(spring.k);
        }
        for (s, k) in self.springs.iter_mut().zip(new) {
            s.k = k;
        }
        Ok(())
    }

    /// Number of springs whose ends lie in different particle blocks.
    pub fn crossing_springs(&self) -> usize {
        self.layout.crossing(self.springs.len())
    }

    /// Number of springs whose ends lie in blocks that are not neighbours: these are summed
    /// serially, the rest in parallel. Number particles so that neighbours are close (a grid row
    /// by row, the layers interleaved) to keep it near zero.
    pub fn far_springs(&self) -> usize {
        self.layout.far().len()
    }

    /// Steps taken so far.
    pub fn steps_taken(&self) -> u64 {
        self.step
    }

    /// The shortest positive spring rest length (∞ when there is none).
    pub fn shortest_rest_length(&self) -> f32 {
        self.min_rest
    }

    fn run_parallel(&self) -> bool {
        self.parallel && self.layout.count > 1
    }

    /// Phase 1: every force on every particle, into [`Particles::forces`].
    ///
    /// Four passes over disjoint slices of the force array (see the layout in the crate's
    /// determinism notes): blocks, even block pairs, odd block pairs, far springs.
    pub fn compute_forces(&mut self) {
        let _span = tracing::trace_span!("forces").entered();
        let parallel = self.run_parallel();
        let layout = &self.layout;
        let bl = layout.block_len;
        let Particles {
            position,
            mass,
            force,
            ..
        } = &mut self.particles;
        let ctx = ForceContext {
            position,
            mass,
            external: &self.external,
            gravity: self.gravity,
            springs: &self.springs,
            anchors: &self.anchors,
            layout,
        };
        over_chunks(parallel, force, bl, |b, chunk| ctx.block(b, chunk));
        if layout.count > 1 {
            let springs = &self.springs;
            // Even pairs: chunk j holds blocks 2j and 2j + 1.
            over_chunks(parallel, force, 2 * bl, |j, chunk| {
                let pair = 2 * j;
                if pair + 1 < layout.count {
                    add_springs(&springs[layout.pair(pair)], position, chunk, pair * bl);
                }
            });
            // Odd pairs: chunk j holds blocks 2j + 1 and 2j + 2.
            over_chunks(parallel, &mut force[bl..], 2 * bl, |j, chunk| {
                let pair = 2 * j + 1;
                if pair + 1 < layout.count {
                    add_springs(&springs[layout.pair(pair)], position, chunk, pair * bl);
                }
            });
            add_springs(&springs[layout.far()], position, force, 0);
        }
        for p in &self.pressures {
            p.add_forces(position, force);
        }

        for v in &self.volumes {
            v.add_forces(position, mass, force, &mut self.volume_scratch);
        }
    }

    /// Phase 2: `v ← (v + f/m·h)·damping` for free particles. For explicit Euler the old
    /// velocities are kept for phase 4. A non-finite result leaves the particle's velocity as it
    /// was and is reported.
    pub fn update_velocities(&mut self, h: f32) -> Result<(), MssError> {
        let _span = tracing::trace_span!("velocities").entered();
        let p = &mut self.particles;
        if self.integrator == Integrator::ExplicitEuler {
            self.previous_velocity.copy_from_slice(&p.velocity);
        }
        let mut bad = u32::MAX;
        for (i, ((v, f), &w)) in p
            .velocity
            .iter_mut()
            .zip(&p.force)
            .zip(&p.inverse_mass)
            .enumerate()
        {
            if w > 0.0 {
                let nv = (*v + *f * (w * h)) * self.damping;
                if nv.is_finite() {
                    *v = nv;
                } else if bad == u32::MAX {
                    bad = i as u32;
                }
            }
        }
        if bad != u32::MAX {
            return Err(MssError::Diverged {
                step: self.step,
                particle: bad,
            });
        }
        Ok(())
    }

    /// Phase 4: `x ← x + v·h` (explicit Euler: the velocity from before phase 2), and the step's
    /// displacement sums. Ends the step.
    pub fn update_positions(&mut self, h: f32) -> Result<StepReport, MssError> {
        let _span = tracing::trace_span!("positions").entered();
        let p = &mut self.particles;
        let used = match self.integrator {
            Integrator::ExplicitEuler => &self.previous_velocity,
            Integrator::SymplecticEuler => &p.velocity,
        };
        let mut sums = BlockSums::EMPTY;
        for (i, (x, v)) in p.position.iter_mut().zip(used).enumerate() {
            let dx = *v * h;
            let nx = *x + dx;
            if nx.is_finite() {
                *x = nx;
                let m = dx.length_squared();
                sums.displacement += f64::from(m.sqrt());
                sums.max_move_sq = sums.max_move_sq.max(m);
            } else if sums.bad == u32::MAX {
                sums.bad = i as u32;
            }
        }
        self.finish(&[sums], h)
    }

    fn finish(&mut self, blocks: &[BlockSums], h: f32) -> Result<StepReport, MssError> {
        let step = self.step;
        self.step += 1;
        let mut report = StepReport {
            step,
            h,
            displacement: 0.0,
            max_move: 0.0,
        };
        for b in blocks {
            if b.bad != u32::MAX {
                return Err(MssError::Diverged {
                    step,
                    particle: b.bad,
                });
            }
            report.displacement += b.displacement;
            report.max_move = report.max_move.max(b.max_move_sq);
        }
        report.max_move = report.max_move.sqrt();
        Ok(report)
    }

    /// One whole step (phases 1, 2, 4) with time step `h` (s), velocities and positions updated in
    /// one sweep.
    pub fn step(&mut self, h: f32) -> Result<StepReport, MssError> {
        let _span = tracing::debug_span!("mss_step", step = self.step).entered();
        self.compute_forces();
        let _integrate = tracing::trace_span!("integrate").entered();
        let ctx = IntegrateContext {
            h,
            damping: self.damping,
            explicit: self.integrator == Integrator::ExplicitEuler,
        };
        let bl = self.layout.block_len;
        let p = &mut self.particles;
        let sums = &mut self.block_sums;
        macro_rules! serial_blocks {
            () => {
                p.position
                    .chunks_mut(bl)
                    .zip(p.velocity.chunks_mut(bl))
                    .zip(p.force.chunks(bl).zip(p.inverse_mass.chunks(bl)))
                    .zip(sums.iter_mut())
                    .enumerate()
            };
        }
        #[cfg(feature = "parallel")]
        if self.parallel && self.layout.count > 1 {
            use rayon::prelude::*;
            p.position
                .par_chunks_mut(bl)
                .zip(p.velocity.par_chunks_mut(bl))
                .zip(p.force.par_chunks(bl).zip(p.inverse_mass.par_chunks(bl)))
                .zip(sums.par_iter_mut())
                .enumerate()
                .for_each(|(b, (((x, v), (f, w)), s))| *s = ctx.block(b * bl, x, v, f, w));
        } else {
            for (b, (((x, v), (f, w)), s)) in serial_blocks!() {
                *s = ctx.block(b * bl, x, v, f, w);
            }
        }
        #[cfg(not(feature = "parallel"))]
        for (b, (((x, v), (f, w)), s)) in serial_blocks!() {
            *s = ctx.block(b * bl, x, v, f, w);
        }
        drop(_integrate);
        let sums = std::mem::take(&mut self.block_sums);
        let report = self.finish(&sums, h);
        self.block_sums = sums;
        report
    }

    /// One step with the caller's collision handling between the velocity and the position
    /// updates (phase 3): `collide` gets the particles after phase 2 and may change velocities
    /// (and positions). With a `collide` that does nothing the result equals
    /// [`MassSpringSystem::step`]'s bit for bit.
    pub fn step_with(
        &mut self,
        h: f32,
        collide: impl FnOnce(&mut Particles),
    ) -> Result<StepReport, MssError> {
        let _span = tracing::debug_span!("mss_step", step = self.step).entered();
        self.compute_forces();
        self.update_velocities(h)?;
        {
            let _c = tracing::trace_span!("collisions").entered();
            collide(&mut self.particles);
        }
        self.update_positions(h)
    }

    /// Whether the last parallel-capable phase would run in parallel.
    pub fn is_parallel(&self) -> bool {
        self.run_parallel()
    }
}

/// Runs `f(j, chunk)` over the `size`-long chunks of `data`, on rayon's pool when `parallel`.
fn over_chunks(
    parallel: bool,
    data: &mut [Vec3A],
    size: usize,
    f: impl Fn(usize, &mut [Vec3A]) + Sync + Send,
) {
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        data.par_chunks_mut(size)
            .enumerate()
            .for_each(|(j, chunk)| f(j, chunk));
        return;
    }
    #[cfg(not(feature = "parallel"))]
    let _ = parallel;
    for (j, chunk) in data.chunks_mut(size).enumerate() {
        f(j, chunk);
    }
}

/// What the force phase of one block reads.
struct ForceContext<'a> {
    position: &'a [Vec3A],
    mass: &'a [f32],
    external: &'a [Vec3A],
    gravity: Vec3A,
    springs: &'a [Spring],
    anchors: &'a [AnchorRecord],
    layout: &'a Layout,
}

impl ForceContext<'_> {
    /// Block `b`'s particle forces: gravity, external, anchors, then its internal springs.
    fn block(&self, b: usize, force: &mut [Vec3A]) {
        let start = b * self.layout.block_len;
        let mass = &self.mass[start..start + force.len()];
        for (f, &m) in force.iter_mut().zip(mass) {
            *f = self.gravity * m;
        }
        if !self.external.is_empty() {
            for (f, e) in force.iter_mut().zip(&self.external[start..]) {
                *f += *e;
            }
        }
        let anchors = &self.anchors[self.layout.anchor_start[b]..self.layout.anchor_start[b + 1]];
        for a in anchors {
            let i = a.particle as usize;
            force[i - start] += (a.target - self.position[i]) * a.k;
        }
        add_springs(
            &self.springs[self.layout.internal(b)],
            self.position,
            force,
            start,
        );
    }
}

/// Eq. (4) for each spring, scattered into `force`, whose first entry is particle `start`.
///
/// Two things keep this loop fast (≈ 3× the naive scatter):
/// - Springs go in batches of four: the square roots and divisions of a batch are written as
///   lane arrays, which the compiler turns into one packed `sqrt` and one packed `div` — the
///   divide unit is the bottleneck of a spring loop, and packed it serves four springs at once.
/// - The springs come sorted by their first particle `a` (with `a < b`), so a run of springs
///   shares `a`: its force is summed in a register and stored once per run, instead of chaining
///   every spring of the run on a store-to-load round trip through `force[a]`.
#[inline]
fn add_springs(springs: &[Spring], position: &[Vec3A], force: &mut [Vec3A], start: usize) {
    let Some(first) = springs.first() else {
        return;
    };
    let mut current = first.a as usize;
    let mut on_a = Vec3A::ZERO;
    let mut apply = |a: usize, b: usize, f: Vec3A| {
        if a != current {
            force[current - start] += on_a;
            on_a = Vec3A::ZERO;
            current = a;
        }
        on_a += f;
        force[b - start] -= f;
    };
    let mut batches = springs.chunks_exact(4);
    for batch in &mut batches {
        let d: [Vec3A; 4] =
            std::array::from_fn(|i| position[batch[i].b as usize] - position[batch[i].a as usize]);
        let len2: [f32; 4] = std::array::from_fn(|i| d[i].length_squared());
        let mut scale = [0.0f32; 4];
        for i in 0..4 {
            // k (1 − l/|d|), and 0·l when |d| = 0 (see `spring_force`).
            let inv = 1.0 / len2[i].sqrt();
            let inv = if len2[i] > 0.0 { inv } else { 0.0 };
            scale[i] = batch[i].k * (1.0 - batch[i].rest * inv);
        }
        for i in 0..4 {
            apply(batch[i].a as usize, batch[i].b as usize, d[i] * scale[i]);
        }
    }
    for s in batches.remainder() {
        let (a, b) = (s.a as usize, s.b as usize);
        apply(a, b, spring_force(position[a], position[b], s.rest, s.k));
    }
    force[current - start] += on_a;
}

/// What the fused velocity + position update of one block reads.
#[derive(Clone, Copy)]
struct IntegrateContext {
    h: f32,
    damping: f32,
    explicit: bool,
}

impl IntegrateContext {
    #[inline]
    fn block(
        &self,
        start: usize,
        position: &mut [Vec3A],
        velocity: &mut [Vec3A],
        force: &[Vec3A],
        inverse_mass: &[f32],
    ) -> BlockSums {
        // Four partial sums (by particle index mod 4) so the additions do not wait on each other;
        // they are combined in a fixed order, so the result does not depend on threads.
        let mut lanes = [0.0f64; 4];
        let mut max_move_sq = 0.0f32;
        let mut bad = u32::MAX;
        let h = self.h;
        for (i, (((x, v), f), &w)) in position
            .iter_mut()
            .zip(velocity.iter_mut())
            .zip(force)
            .zip(inverse_mass)
            .enumerate()
        {
            let old = *v;
            let new = if w > 0.0 {
                (old + *f * (w * h)) * self.damping
            } else {
                old
            };
            let dx = if self.explicit { old } else { new } * h;
            let nx = *x + dx;
            if new.is_finite() && nx.is_finite() {
                *v = new;
                *x = nx;
                let m = dx.length_squared();
                lanes[i & 3] += f64::from(m.sqrt());
                max_move_sq = max_move_sq.max(m);
            } else if bad == u32::MAX {
                bad = (start + i) as u32;
            }
        }
        BlockSums {
            displacement: (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]),
            max_move_sq,
            bad,
        }
    }
}

impl MassSpringSystem {
    /// Sets the step counter back (after a redone step).
    pub(crate) fn rewind_to(&mut self, step: u64) {
        self.step = step;
    }
}
