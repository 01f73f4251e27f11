#include "dem/contact.hpp"

#include <mutex>
#include <utility>
#include <vector>

namespace sandflow {

Real clamped_restitution(Real beta) {
  // delta: overlap, u: its rate (approach positive), time in units of 1/omega_n
  const Real h = 1e-4;
  auto acc = [beta](Real d, Real u) {
    const Real f = d + 2 * beta * u;
    return f > 0 ? -f : 0.0;
  };
  Real d = 0, u = 1;
  for (long k = 0; k < 10'000'000; ++k) {
    // the contact ends when the force vanishes on the way out (or the overlap does)
    if (u < 0 && (d + 2 * beta * u <= 0 || d <= 0)) return -u;
    const Real k1d = u, k1u = acc(d, u);
    const Real k2d = u + h / 2 * k1u, k2u = acc(d + h / 2 * k1d, u + h / 2 * k1u);
    const Real k3d = u + h / 2 * k2u, k3u = acc(d + h / 2 * k2d, u + h / 2 * k2u);
    const Real k4d = u + h * k3u, k4u = acc(d + h * k3d, u + h * k3u);
    d += h / 6 * (k1d + 2 * k2d + 2 * k3d + k4d);
    u += h / 6 * (k1u + 2 * k2u + 2 * k3u + k4u);
  }
  return 0;
}

Real damping_beta(Real restitution) {
  if (restitution >= 1) return 0;
  // Each answer is kept: the bisection below integrates 40 collisions, about 18 ms, and every
  // World asks twice as it is built (the test suite and a calibration build hundreds of them)
  static std::mutex guard;
  static std::vector<std::pair<Real, Real>> known;  // (restitution, beta)
  {
    const std::lock_guard lock(guard);
    for (const auto& [e, beta] : known)
      if (e == restitution) return beta;
  }
  // clamped_restitution falls monotonically from 1 (beta = 0) towards 0: bisect
  Real lo = 0, hi = kMaxDampingBeta;
  for (int it = 0; it < 40; ++it) {
    const Real mid = 0.5 * (lo + hi);
    if (clamped_restitution(mid) > restitution) lo = mid;
    else hi = mid;
  }
  const Real beta = 0.5 * (lo + hi);
  const std::lock_guard lock(guard);
  known.emplace_back(restitution, beta);
  return beta;
}

Real smallest_restitution() {
  static const Real e = clamped_restitution(kMaxDampingBeta);
  return e;
}

}  // namespace sandflow
