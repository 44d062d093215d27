#include "physics/rk4.h"

namespace ponyhop {

namespace {

// y + c k, where k holds a state's derivative: (v, q', a, alpha) taken from `rate` (state whose
// velocities are the position derivatives) and `acc`.
void advance(const State& y0, double c, const State& rate, const Accelerations& acc, State& out) {
  for (size_t i = 0; i < y0.size(); ++i) {
    out[i].x = y0[i].x + c * rate[i].v;
    out[i].q.coeffs() = y0[i].q.coeffs() + c * quaternionRate(rate[i].w, rate[i].q).coeffs();
    out[i].v = y0[i].v + c * acc[i].a;
    out[i].w = y0[i].w + c * acc[i].alpha;
  }
}

}  // namespace

void rk4Step(double t, double h, const Accelerations& k1, const AccelerationFunction& f, State& state, Rk4Work& work) {
  State &y1 = work.y1, &y2 = work.y2, &y3 = work.y3, &y4 = work.y4;
  Accelerations &k2 = work.k2, &k3 = work.k3, &k4 = work.k4;
  y1 = state;  // stage 1 is the initial state; its rates are (v, q', k1)
  for (State* y : {&y2, &y3, &y4}) y->resize(state.size());
  for (Accelerations* k : {&k2, &k3, &k4}) k->resize(state.size());

  advance(state, 0.5 * h, y1, k1, y2);
  f(t + 0.5 * h, y2, k2);
  advance(state, 0.5 * h, y2, k2, y3);
  f(t + 0.5 * h, y3, k3);
  advance(state, h, y3, k3, y4);
  f(t + h, y4, k4);

  // y(t + h) = y + h/6 (k1 + 2 k2 + 2 k3 + k4); each stage's position rate is its own (v, q').
  for (size_t i = 0; i < state.size(); ++i) {
    BodyState& s = state[i];
    const BodyState &s1 = y1[i], &s2 = y2[i], &s3 = y3[i], &s4 = y4[i];
    s.x += h / 6.0 * (s1.v + 2.0 * s2.v + 2.0 * s3.v + s4.v);
    s.q.coeffs() += h / 6.0 *
                    (quaternionRate(s1.w, s1.q).coeffs() + 2.0 * quaternionRate(s2.w, s2.q).coeffs() +
                     2.0 * quaternionRate(s3.w, s3.q).coeffs() + quaternionRate(s4.w, s4.q).coeffs());
    s.q.normalize();
    s.v += h / 6.0 * (k1[i].a + 2.0 * k2[i].a + 2.0 * k3[i].a + k4[i].a);
    s.w += h / 6.0 * (k1[i].alpha + 2.0 * k2[i].alpha + 2.0 * k3[i].alpha + k4[i].alpha);
  }
}

}  // namespace ponyhop
