// K iterations of the preconditioned primal-dual method for anisotropic TGV-L1:
//   min_u,v  lambda |rho(u)| + alpha1 |D grad u - v| + alpha0 |grad v|
// with rho(u) = iz + (u - u0) iu. Each iteration is a dual pass then a primal pass over
// all pixels; each pass reads neighbours only from the other pass's variables, so
// pixels are independent (Jacobi) and the order of evaluation does not matter.
#include <cmath>

#include "cpu_backend.hpp"
#include "operators.hpp"

namespace cs::cpu {

namespace {

void projectUnitBall(float* v, int n) {
  float s = 0.f;
  for (int i = 0; i < n; ++i) s += v[i] * v[i];
  float norm = std::sqrt(s);
  if (norm > 1.f)
    for (int i = 0; i < n; ++i) v[i] /= norm;
}

struct Vars {
  const View &u, &uBar, &v, &vBar, &p, &q, &u0, &iu, &iz, &tensor, &steps, &mask;
};

void dualUpdate(const Vars& s, const PrimalDualParams& prm, const PrimalDualStep& step, int x, int y) {
  const View& t = s.tensor;
  float gx = gradX(s.uBar, s.mask, x, y, 0), gy = gradY(s.uBar, s.mask, x, y, 0);
  float a1 = t.at(x, y, 0) * gx + t.at(x, y, 1) * gy - s.vBar.at(x, y, 0);
  float a2 = t.at(x, y, 1) * gx + t.at(x, y, 2) * gy - s.vBar.at(x, y, 1);
  float p[2] = {s.p.at(x, y, 0) + step.sigmaScale * s.steps.at(x, y, 2) * prm.alpha1 * a1,
                s.p.at(x, y, 1) + step.sigmaScale * s.steps.at(x, y, 3) * prm.alpha1 * a2};
  projectUnitBall(p, 2);
  s.p.at(x, y, 0) = p[0];
  s.p.at(x, y, 1) = p[1];

  // Each row of alpha0 grad v has two entries of size alpha0: sigma_q = 1 / (2 alpha0).
  const float sigmaQ = step.sigmaScale * 0.5f / prm.alpha0;
  float q[4] = {gradX(s.vBar, s.mask, x, y, 0), gradY(s.vBar, s.mask, x, y, 0), gradX(s.vBar, s.mask, x, y, 1),
                gradY(s.vBar, s.mask, x, y, 1)};
  for (int i = 0; i < 4; ++i) q[i] = s.q.at(x, y, i) + sigmaQ * prm.alpha0 * q[i];
  projectUnitBall(q, 4);
  for (int i = 0; i < 4; ++i) s.q.at(x, y, i) = q[i];
}

void primalUpdate(const Vars& s, const PrimalDualParams& prm, const PrimalDualStep& step, int x, int y) {
  const View& t = s.tensor;
  auto dpX = [&](int i, int j) { return t.at(i, j, 0) * s.p.at(i, j, 0) + t.at(i, j, 1) * s.p.at(i, j, 1); };
  auto dpY = [&](int i, int j) { return t.at(i, j, 1) * s.p.at(i, j, 0) + t.at(i, j, 2) * s.p.at(i, j, 1); };
  const float tauU = step.tauScale * s.steps.at(x, y, 0);
  const float tauV = step.tauScale * s.steps.at(x, y, 1);

  const float uOld = s.u.at(x, y);
  float uHat = uOld + tauU * prm.alpha1 * divergence(s.mask, x, y, dpX, dpY);
  float uNew = dataProx(uHat, s.u0.at(x, y), s.iu.at(x, y), s.iz.at(x, y), tauU * prm.lambda);
  s.u.at(x, y) = uNew;
  s.uBar.at(x, y) = uNew + step.theta * (uNew - uOld);

  for (int c = 0; c < 2; ++c) {
    auto qx = [&](int i, int j) { return s.q.at(i, j, 2 * c); };
    auto qy = [&](int i, int j) { return s.q.at(i, j, 2 * c + 1); };
    const float vOld = s.v.at(x, y, c);
    float vNew = vOld + tauV * (prm.alpha1 * s.p.at(x, y, c) + prm.alpha0 * divergence(s.mask, x, y, qx, qy));
    s.v.at(x, y, c) = vNew;
    s.vBar.at(x, y, c) = vNew + step.theta * (vNew - vOld);
  }
}

}  // namespace

void primalDual(const View& u, const View& uBar, const View& v, const View& vBar, const View& p, const View& q,
                const View& u0, const View& iu, const View& iz, const View& tensor, const View& steps, const View& mask,
                const PrimalDualParams& params) {
  const Vars s{u, uBar, v, vBar, p, q, u0, iu, iz, tensor, steps, mask};
  for (const PrimalDualStep& step : params.schedule) {
    parallelRows(mask.height, [&](int y) {
      for (int x = 0; x < mask.width; ++x)
        if (masked(mask, x, y)) dualUpdate(s, params, step, x, y);
    });
    parallelRows(mask.height, [&](int y) {
      for (int x = 0; x < mask.width; ++x)
        if (masked(mask, x, y)) primalUpdate(s, params, step, x, y);
    });
  }
}

}  // namespace cs::cpu
