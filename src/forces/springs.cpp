// Provot's springs, eq. 1: Hooke's law plus damping projected on the spring.
#include "../detail.hpp"

namespace wetcloth::detail {

void add_spring_forces(const SpringSet& s, const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                       std::vector<Vec3>& f, std::vector<Mat3>* damping) {
  const double k = s.k, kd = s.damping;
  for (std::size_t e = 0; e < s.size(); ++e) {
    const int a = s.a[e], b = s.b[e];
    const Vec3 d = x[b] - x[a];
    const double len = d.norm();
    if (len <= 0) continue;
    const Vec3 u = d / len;
    // F_a = u (k_s (|d| - l0) + k_d (v_b - v_a)·u), F_b = -F_a
    const Vec3 fa = u * (k * (len - s.rest[e]) + kd * (v[b] - v[a]).dot(u));
    f[a] += fa;
    f[b] -= fa;
    if (damping) {  // ∂F_a/∂v_a = -k_d u uᵀ, the same for b
      const Mat3 c = kd * u * u.transpose();
      (*damping)[a] += c;
      (*damping)[b] += c;
    }
  }
}

}  // namespace wetcloth::detail
