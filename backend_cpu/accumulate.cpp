#include <algorithm>

#include "cpu_backend.hpp"

namespace cs::cpu {

// Limit the increment of this warp and advance the 2-D warp along the tangent: small
// steps keep the point on the epipolar curve (paper Sec. III-C).
void accumulate(const View& u, const View& w, const View& u0, const View& tangent, const View& mask, float duMax) {
  parallelRows(u.height, [&](int y) {
    for (int x = 0; x < u.width; ++x) {
      if (!masked(mask, x, y)) continue;
      float du = std::min(std::max(u.at(x, y) - u0.at(x, y), -duMax), duMax);
      u.at(x, y) = u0.at(x, y) + du;
      w.at(x, y, 0) += du * tangent.at(x, y, 0);
      w.at(x, y, 1) += du * tangent.at(x, y, 1);
    }
  });
}

}  // namespace cs::cpu
