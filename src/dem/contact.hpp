// The contact law of docs/design.md §3 as pure functions of two bodies' state and the contact's
// history, so that it can be tested against closed forms and shared by grain pairs and walls.
//
//   normal:      F_n = k_n delta - c_n v_n, clamped at 0 (no pull),
//                c_n = 2 sqrt(m_eff k_n) beta, beta = -ln e / sqrt(pi^2 + ln^2 e)
//   tangential:  spring on the accumulated displacement xi (rotated into the current tangent
//                plane each step), F_t = -k_t xi - c_t v_t, capped at mu F_n (xi rescaled on slip)
//   rolling:     spring-dashpot on the accumulated rolling displacement psi ("EPSD" kind),
//                F_r = -k_r psi - c_r v_r capped at mu_r F_n; torque R_eff n x F_r
//   twisting:    a dashpot on the relative spin about n, T = -c_t R_eff^2 (w_i - w_j).n n,
//                capped at mu_tw R_eff F_n. No spring: a heap holds no static twist worth the
//                history it would cost each listed pair; the dashpot alone stops a grain spinning
//                about its contact's normal, which without it spins for ever (a lone grain on a
//                floor). Its stability: c_t R_eff^2 dt / I <= c_t dt / (0.4 m), as the tangential
//                dashpot's.
//
// Conventions: n points from body j to body i; the results are the force and torques on i, and
// the torque on j (the force on j is the opposite of the force on i).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/vec3.hpp"

namespace sandflow {

struct ContactParams {
  Real k_n = 0;     ///< normal stiffness [N/m]
  Real beta = 0;    ///< damping factor from restitution [-]
  Real k_t = 0;     ///< tangential stiffness [N/m]
  Real c_t_ratio = 0.5;  ///< c_t / c_n [-]
  Real mu = 0;      ///< Coulomb friction [-]
  Real k_r = 0;     ///< rolling stiffness [N/m]
  Real c_r_ratio = 1.0;  ///< c_r / c_t [-]
  Real mu_r = 0;    ///< rolling friction [-]
  Real mu_tw = 0;   ///< twisting friction [-] (0: none)
};

/// beta of c_n = 2 sqrt(m_eff k_n) beta for restitution e of the *unclamped* linear dashpot,
/// e = exp(-beta pi / sqrt(1 - beta^2)).
inline Real damping_beta_unclamped(Real restitution) {
  const Real le = std::log(restitution);
  return -le / std::sqrt(kPi * kPi + le * le);
}

/// Restitution of one collision under the law as used here, with F_n clamped at 0: the clamp
/// removes the dashpot's pull at the end of the contact, so grains leave faster than the
/// unclamped formula says (e = 0.3 becomes ~0.40). Integrates the dimensionless collision
/// delta'' = -(delta + 2 beta delta') (while positive) with RK4 until the force vanishes.
Real clamped_restitution(Real beta);

/// The largest damping factor damping_beta gives: restitutions below what it reaches
/// (smallest_restitution()) are refused by the scene loader.
constexpr Real kMaxDampingBeta = 50;
/// beta such that a head-on collision under the clamped law has restitution e in
/// [smallest_restitution(), 1].
Real damping_beta(Real restitution);
/// The restitution of the clamped law at kMaxDampingBeta.
Real smallest_restitution();

/// Contact duration of a linear spring-dashpot (undamped): t_c = pi sqrt(m_eff / k_n) [s].
inline Real contact_time(Real m_eff, Real k_n) { return kPi * std::sqrt(m_eff / k_n); }

/// History of one contact, kept from the moment it opens.
struct ContactHistory {
  Vec3 xi;   ///< accumulated tangential displacement [m]
  Vec3 psi;  ///< accumulated rolling displacement [m]
};

/// Energy stored in the springs of a contact with overlap delta (normal, tangential, rolling) [J].
inline Real elastic_energy(const ContactParams& p, Real delta, const ContactHistory& h) {
  const Real k_r = p.mu_r > 0 ? p.k_r : 0;  // (without rolling resistance psi is not kept)
  return 0.5 * (p.k_n * delta * delta + p.k_t * norm2(h.xi) + k_r * norm2(h.psi));
}

/// Damping coefficient of the normal dashpot: c_n = 2 sqrt(m_eff k_n) beta [kg/s].
inline Real normal_damping(const ContactParams& p, Real m_eff) {
  return 2.0 * std::sqrt(m_eff * p.k_n) * p.beta;
}

struct ContactGeometry {
  Vec3 n;          ///< unit normal, from j to i
  Real delta;      ///< overlap > 0 [m]
  Real arm_i;      ///< distance from i's centre to the contact point [m]
  Real arm_j;      ///< distance from j's centre to the contact point (0 for a wall) [m]
  Real c_n;        ///< normal damping coefficient, normal_damping(p, m_eff) [kg/s]
  Real r_eff;      ///< effective rolling radius [m]
};

/// The result, kept compact for the pair kernel: the torques follow from q and t_roll.
struct ContactForce {
  Vec3 force_i;    ///< force on i (on j: the opposite) [N]
  Vec3 q;          ///< n x F_t: the tangential torque on a body is -arm * q [N]
  Vec3 t_roll;     ///< rolling torque on i (on j: the opposite) [N m]
  Real f_n;        ///< normal force magnitude (>= 0) [N]
  bool sliding;    ///< the tangential force is at the Coulomb limit mu F_n: the contact slips

  Vec3 torque_i(const ContactGeometry& g) const { return q * (-g.arm_i) + t_roll; }
  Vec3 torque_j(const ContactGeometry& g) const { return q * (-g.arm_j) - t_roll; }
};

/// Rotates a history vector into the plane normal to n, keeping its length: the projection p onto
/// the plane scaled by |a| / |p| = 1 / sqrt(1 - w), w = (a.n)^2 / |a|^2. The normal turns little
/// in one step, so w is tiny and 1 / sqrt(1 - w) = 1 + w/2 to 4e-13 relative; the exact root is
/// kept for large turns. 1 / |a|^2 needs only the stored history, not n: the division runs
/// beside the normal's square root instead of after it (the sweep waits on each contact's chain
/// of dependent operations, docs/performance.md).
inline Vec3 rotate_into_plane(const Vec3& a, const Vec3& n) {
  const Real a2 = norm2(a);
  const Real inv_a2 = a2 > 0 ? 1 / a2 : 0.0;
  const Real an = dot(a, n);
  const Vec3 p = a - n * an;
  const Real w = an * an * inv_a2;
  if (w < 1e-6) return p * (1 + 0.5 * w);
  return w < 1 ? p * (1 / std::sqrt(1 - w)) : Vec3{};
}

/// Spring-dashpot on a history vector s with a Coulomb-type cap: returns the force and updates s,
/// and sets `capped` when the cap acted. On slip the history is rescaled so that the spring alone
/// would give the capped force.
inline Vec3 capped_spring(Vec3& s, const Vec3& rate, Real k, Real c, Real cap, Real dt,
                          bool& capped) {
  s += rate * dt;
  Vec3 f = s * (-k) - rate * c;
  const Real f2 = norm2(f);
  capped = f2 > cap * cap;
  if (capped) {
    f *= (f2 > 0 ? cap / std::sqrt(f2) : 0.0);
    // (a spring of no stiffness, k_t_ratio = 0, holds no stretch: 1/k would make it infinite)
    s = k > 0 ? (f + rate * c) * (-1.0 / k) : Vec3{};
  }
  return f;
}

/// The full law. v_rel = v_i - v_j (centres); w_i, w_j angular velocities. With kRolling = false
/// the rolling and twisting parts are skipped (a compile-time switch: without rolling or twisting
/// resistance they cost nothing; the twisting torque rides on the rolling one, t_roll). Inlined by
/// force: GCC 12 keeps the rolling variant out of line in the sweep, a call per contact that cost
/// 6-12 % of a surface run of the floor (docs/performance.md).
template <bool kRolling>
[[gnu::always_inline]] inline ContactForce contact_force(const ContactParams& p, const ContactGeometry& g,
                                  const Vec3& v_rel, const Vec3& w_i, const Vec3& w_j,
                                  ContactHistory& h, Real dt) {
  const Vec3& n = g.n;
  // relative velocity of the surfaces at the contact point
  const Vec3 v_c = v_rel - cross(w_i * g.arm_i + w_j * g.arm_j, n);
  const Real v_n = dot(v_c, n);
  const Vec3 v_t = v_c - n * v_n;

  // normal: spring-dashpot, never pulling
  Real f_n = p.k_n * g.delta - g.c_n * v_n;
  if (f_n < 0) f_n = 0;

  // tangential: history spring with Coulomb cap
  const Real c_t = p.c_t_ratio * g.c_n;
  h.xi = rotate_into_plane(h.xi, n);
  ContactForce out;
  const Vec3 f_t = capped_spring(h.xi, v_t, p.k_t, c_t, p.mu * f_n, dt, out.sliding);
  out.f_n = f_n;
  out.force_i = n * f_n + f_t;
  out.q = cross(n, f_t);
  if constexpr (kRolling) {
    if (p.mu_r > 0) {  // (a contact without it, beside others with it, keeps psi at 0)
      // rolling: relative rolling velocity of the surfaces, spring-dashpot capped at mu_r R F_n
      const Vec3 v_r = cross(w_i - w_j, n) * g.r_eff;
      h.psi = rotate_into_plane(h.psi, n);
      const Real c_r = p.c_r_ratio * c_t;
      bool rolls;  // (a rolling contact at its cap rolls; it does not slip)
      const Vec3 f_r = capped_spring(h.psi, v_r, p.k_r, c_r, p.mu_r * f_n, dt, rolls);
      out.t_roll = cross(n, f_r) * g.r_eff;
    }
    if (p.mu_tw > 0) {
      const Real cap = p.mu_tw * g.r_eff * f_n;
      const Real t = c_t * g.r_eff * g.r_eff * dot(w_i - w_j, n);
      out.t_roll -= n * std::clamp(t, -cap, cap);
    }
  }
  return out;
}

}  // namespace sandflow
