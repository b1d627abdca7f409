// Kernel properties: normalisation, gradient antisymmetry and consistency, compact support, for mixed radii.
#include <gtest/gtest.h>

#include <random>

#include "sim/kernels.h"

using fp::sim::CubicSpline;
using fp::sim::Real;
using fp::sim::Vec3;

namespace {
// midpoint quadrature of f over the cube [-H, H]^3 with m cells a side
template <class F>
double integrate(double H, int m, F&& f) {
  const double d = 2.0 * H / m;
  double sum = 0.0;
  for (int z = 0; z < m; ++z)
    for (int y = 0; y < m; ++y)
      for (int x = 0; x < m; ++x) {
        const Vec3 p(Real(-H + d * (x + 0.5)), Real(-H + d * (y + 0.5)), Real(-H + d * (z + 0.5)));
        sum += f(p) * d * d * d;
      }
  return sum;
}
}  // namespace

TEST(KernelTest, IntegratesToOneForSeveralSupports) {
  for (double H : {0.04, 0.1, 0.3}) {
    const double integral =
        integrate(H, 120, [&](const Vec3& p) { return double(CubicSpline::w(p.norm(), Real(H))); });
    EXPECT_NEAR(integral, 1.0, 2e-3) << "H = " << H;
  }
}

TEST(KernelTest, GradientIntegratesToZeroAndFirstMomentIsMinusIdentity) {
  // int grad W dV = 0 and int x (x)^T grad W dV = -I: the properties SPH derivatives rely on
  const double H = 0.1;
  const double gx =
      integrate(H, 100, [&](const Vec3& p) { return double(CubicSpline::grad(p, Real(H)).x()); });
  const double mxx =
      integrate(H, 100, [&](const Vec3& p) { return double(p.x() * CubicSpline::grad(p, Real(H)).x()); });
  const double mxy =
      integrate(H, 100, [&](const Vec3& p) { return double(p.x() * CubicSpline::grad(p, Real(H)).y()); });
  EXPECT_NEAR(gx, 0.0, 1e-6);
  EXPECT_NEAR(mxx, -1.0, 5e-3);
  EXPECT_NEAR(mxy, 0.0, 1e-6);
}

TEST(KernelTest, GradientIsAntisymmetricAndMatchesFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const Real H = Real(0.05 + 0.25 * (u(rng) + 1.0));
    Vec3 x = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))) * H * Real(0.6);
    const Vec3 g = CubicSpline::grad(x, H);
    const Vec3 gm = CubicSpline::grad(-x, H);
    EXPECT_NEAR((g + gm).norm(), 0.0, 1e-6 * g.norm() + 1e-12);
    // central differences in double precision of the same formula
    const double e = 1e-4 * H;
    for (int d = 0; d < 3; ++d) {
      Vec3 xp = x, xm = x;
      xp[d] += Real(e);
      xm[d] -= Real(e);
      const double fd = (double(CubicSpline::w(xp.norm(), H)) - double(CubicSpline::w(xm.norm(), H))) /
                        (double(xp[d]) - double(xm[d]));
      EXPECT_NEAR(double(g[d]), fd, 2e-2 * std::abs(fd) + 2e-2 * CubicSpline::w0(H) / H) << "component " << d;
    }
  }
}

TEST(KernelTest, ZeroOutsideSupportAndAtTheOrigin) {
  const Real H = 0.2f;
  EXPECT_EQ(CubicSpline::w(H, H), 0.0f);
  EXPECT_EQ(CubicSpline::w(1.5f * H, H), 0.0f);
  EXPECT_EQ(CubicSpline::gradFactor(H, H), 0.0f);
  EXPECT_EQ(CubicSpline::gradFactor(2.0f * H, H), 0.0f);
  EXPECT_EQ(CubicSpline::gradFactor(0.0f, H), 0.0f);
  EXPECT_GT(CubicSpline::w(0.999f * H, H), 0.0f);
  EXPECT_FLOAT_EQ(CubicSpline::w(0.0f, H), CubicSpline::w0(H));
  // continuity at q = 1/2
  EXPECT_NEAR(CubicSpline::w(0.5f * H - 1e-6f, H), CubicSpline::w(0.5f * H + 1e-6f, H),
              1e-3f * CubicSpline::w0(H));
}

TEST(KernelTest, EvaluateMatchesSeparateCalls) {
  for (Real q = 0.0f; q < 1.2f; q += 0.013f) {
    const Real H = 0.07f;
    Real w, g;
    CubicSpline::evaluate(q * H, H, w, g);
    EXPECT_FLOAT_EQ(w, CubicSpline::w(q * H, H));
    EXPECT_FLOAT_EQ(g, CubicSpline::gradFactor(q * H, H));
  }
}

TEST(KernelTest, MixedSupportPairsAreSymmetric) {
  // a fine particle (H) and a coarse one (3H) see the same kernel value and opposite gradients
  const Real Hf = 0.04f, Hc = 0.12f;
  const Real h = fp::sim::pairSupport(Hf, Hc);
  EXPECT_FLOAT_EQ(h, fp::sim::pairSupport(Hc, Hf));
  EXPECT_FLOAT_EQ(h, 0.08f);
  const Vec3 xij(0.03f, -0.01f, 0.02f);
  EXPECT_FLOAT_EQ(CubicSpline::w(xij.norm(), h), CubicSpline::w((-xij).norm(), h));
  const Vec3 g = CubicSpline::grad(xij, h);
  EXPECT_NEAR((g + CubicSpline::grad(-xij, h)).norm(), 0.0f, 1e-6f * g.norm());
  // scale invariance: a 3x larger particle on a 3x larger lattice has a 27x smaller kernel
  EXPECT_NEAR(CubicSpline::w(3.0f * 0.02f, Hc), CubicSpline::w(0.02f, Hf) / 27.0f, 1e-3f);
}
