#pragma once
// The Newmark family of paper Eqs. 21-22: x = x_hat + 2 alpha beta dt^2 a,
// x_hat = x^n + dt v^n + alpha (1 - 2 beta) dt^2 a^n,
// v^{n+1} = v^n + dt ((1 - gamma) a^n + gamma a^{n+1}).
// Backward Euler is (1, 1/2, 1); mid-point Newmark (1/2, 1/4, 1/2).
#include <string>

namespace bfemp {

struct TimeIntegrator {
  std::string name;
  double alpha = 1.0, beta = 0.5, gamma = 1.0;

  static TimeIntegrator backward_euler() { return {"backward-euler", 1.0, 0.5, 1.0}; }
  static TimeIntegrator newmark(double alpha = 0.5, double beta = 0.25, double gamma = 0.5) {
    return {"newmark", alpha, beta, gamma};
  }
  // Factor of the potential energy in the incremental potential (Eq. 22).
  double potential_scale(double dt) const { return 2.0 * alpha * beta * dt * dt; }
  double predictor_acc_scale(double dt) const { return alpha * (1.0 - 2.0 * beta) * dt * dt; }
};

}  // namespace bfemp
