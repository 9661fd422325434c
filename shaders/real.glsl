// The scalar of the camera-model shaders: double where the device has shaderFloat64
// (compiled with -DCS_DOUBLE, the precision of the oracle), else float. GLSL has no
// double transcendental functions, so sin/cos/atan2/acos are written out here for both.
#ifndef CS_REAL_GLSL
#define CS_REAL_GLSL

#ifdef CS_DOUBLE
#define real double
#define vec2r dvec2
#define vec3r dvec3
#define R(x) double(x)  // only for constants exact in float; precise ones below carry LF
#define D(x, f) x
#define EPS 2.220446049250313e-16LF
#else
#define real float
#define vec2r vec2
#define vec3r vec3
#define R(x) x
#define D(x, f) f
#define EPS 1.1920929e-7
#endif

#define PI_R D(3.14159265358979323846LF, 3.14159265358979323846)

// sin and cos: Cody-Waite reduction by pi/2 and Taylor polynomials on [-pi/4, pi/4]
// (accurate to the last bits of double there; Vulkan's float sin/cos promise only 2^-11).
void sincosr(real x, out real s, out real c) {
  const real kTwoOverPi = D(0.63661977236758134308LF, 0.63661977236758134308);
  const real kPio2Hi = D(1.57079632679489655800e+00LF, 1.57079632679489655800e+00);
  const real kPio2Lo = D(6.12323399573676603587e-17LF, 6.12323399573676603587e-17);
  real k = floor(x * kTwoOverPi + R(0.5));
  real r = (x - k * kPio2Hi) - k * kPio2Lo;
  real r2 = r * r;
  real sr = r * (R(1.0) + r2 * (D(-1.6666666666666666e-01LF, -1.6666666666666666e-01) + r2 * (D(8.3333333333333333e-03LF, 8.3333333333333333e-03) +
           r2 * (D(-1.9841269841269841e-04LF, -1.9841269841269841e-04) + r2 * (D(2.7557319223985891e-06LF, 2.7557319223985891e-06) + r2 * (D(-2.5052108385441719e-08LF, -2.5052108385441719e-08) +
           r2 * (D(1.6059043836821615e-10LF, 1.6059043836821615e-10) + r2 * (D(-7.6471637318198165e-13LF, -7.6471637318198165e-13) + r2 * (D(2.8114572543455206e-15LF, 2.8114572543455206e-15) +
           r2 * D(-8.2206352466243295e-18LF, -8.2206352466243295e-18))))))))));
  real cr = R(1.0) + r2 * (R(-0.5) + r2 * (D(4.1666666666666667e-02LF, 4.1666666666666667e-02) + r2 * (D(-1.3888888888888889e-03LF, -1.3888888888888889e-03) +
           r2 * (D(2.4801587301587302e-05LF, 2.4801587301587302e-05) + r2 * (D(-2.7557319223985891e-07LF, -2.7557319223985891e-07) + r2 * (D(2.0876756987868099e-09LF, 2.0876756987868099e-09) +
           r2 * (D(-1.1470745597729725e-11LF, -1.1470745597729725e-11) + r2 * (D(4.7794773323873853e-14LF, 4.7794773323873853e-14) + r2 * D(-1.5619206968586225e-16LF, -1.5619206968586225e-16)))))))));
  int q = int(k) & 3;
  if (q == 0) { s = sr; c = cr; }
  else if (q == 1) { s = cr; c = -sr; }
  else if (q == 2) { s = -sr; c = -cr; }
  else { s = -cr; c = sr; }
}

// atan(a) for 0 <= a <= 1. Above tan(pi/12), atan a = pi/6 + atan((sqrt3 a - 1) / (a + sqrt3))
// brings the argument to |t| <= tan(pi/12); there the odd Taylor series of atan, t (1 - t^2/3 +
// t^4/5 - ...), loses a factor t^2 <= 0.072 a term: 14 terms reach double's last bits, 6
// float's (Vulkan's own float atan promises only 4096 ulp; GLSL has none in double).
real atanUnit(real a) {
  const real kTanPi12 = D(0.26794919243112270647LF, 0.26794919243112270647);
  const real kSqrt3 = D(1.73205080756887729353LF, 1.73205080756887729353);
  real shift = R(0.0);
  if (a > kTanPi12) {
    a = (kSqrt3 * a - R(1.0)) / (a + kSqrt3);
    shift = PI_R / R(6.0);
  }
  const real t2 = a * a;
#ifdef CS_DOUBLE
  const int kLast = 13;
#else
  const int kLast = 5;
#endif
  real sum = R(1.0) / real(2 * kLast + 1);
  for (int n = kLast - 1; n >= 0; --n) sum = R(1.0) / real(2 * n + 1) - t2 * sum;
  return shift + a * sum;
}

// atan2(y, x) for y >= 0 (the camera models' uses): the smaller of y / |x| and |x| / y
// through atanUnit, then the quadrant.
real atan2r(real y, real x) {
  if (y == R(0.0)) return x >= R(0.0) ? R(0.0) : PI_R;
  const real ax = abs(x);
  const real t = y <= ax ? atanUnit(y / ax) : PI_R / R(2.0) - atanUnit(ax / y);
  return x >= R(0.0) ? t : PI_R - t;
}

// acos(c) for c in [0, 1]; (1 - c)(1 + c) keeps the digits near c = 1.
real acosr(real c) { return atan2r(sqrt((R(1.0) - c) * (R(1.0) + c)), c); }

#endif
