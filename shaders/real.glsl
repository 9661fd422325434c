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

// atan2(y, x) for y >= 0 (every use here).
#ifdef CS_DOUBLE
// fdlibm's atan (s_atan.c) of |y / x|: the argument reduced by one of atan(1/2), atan(1),
// atan(3/2), atan(inf) (the constants in two parts) to |t| < 7/16, then an odd polynomial
// of degree 23; pi minus it for x < 0 (as fdlibm's e_atan2.c). Within a few ulp of double,
// as the three Newton steps on a float estimate it replaces, at two divisions and a
// dozen fused multiply-adds instead of three divisions and three sin/cos.
real atan2r(real y, real x) {
  if (y == 0.0LF) return x >= 0.0LF ? 0.0LF : PI_R;
  double a = y / abs(x);  // +inf at x = 0: atan = pi/2 below
  double hi = 0.0LF, lo = 0.0LF;
  bool reduced = true;
  if (a < 0.4375LF) {
    reduced = false;
  } else if (a < 0.6875LF) {
    hi = 4.63647609000806093515e-01LF; lo = 2.26987774529616870924e-17LF;
    a = (2.0LF * a - 1.0LF) / (2.0LF + a);
  } else if (a < 1.1875LF) {
    hi = 7.85398163397448278999e-01LF; lo = 3.06161699786838301793e-17LF;
    a = (a - 1.0LF) / (a + 1.0LF);
  } else if (a < 2.4375LF) {
    hi = 9.82793723247329054082e-01LF; lo = 1.39033110312309984516e-17LF;
    a = (a - 1.5LF) / (1.0LF + 1.5LF * a);
  } else {
    hi = 1.57079632679489655800e+00LF; lo = 6.12323399573676603587e-17LF;
    a = -1.0LF / a;
  }
  const double z = a * a, w = z * z;
  const double s1 = z * (3.33333333333329318027e-01LF + w * (1.42857142725034663711e-01LF +
                   w * (9.09088713343650656196e-02LF + w * (6.66107313738753120669e-02LF +
                   w * (4.97687799461593236017e-02LF + w * 1.62858201153657823623e-02LF)))));
  const double s2 = w * (-1.99999999998764832476e-01LF + w * (-1.11111104054623557880e-01LF +
                   w * (-7.69187620504482999495e-02LF + w * (-5.83357013379057348645e-02LF +
                   w * -3.65315727442169155270e-02LF))));
  const double t = reduced ? hi - ((a * (s1 + s2) - lo) - a) : a - a * (s1 + s2);
  // x < 0: pi - t, with pi's low part (e_atan2.c's pi - (z - pi_lo)).
  return x >= 0.0LF ? t : 3.1415926535897931160E+00LF - (t - 1.2246467991473531772E-16LF);
}
#else
// A float estimate refined by Newton steps on x sin(t) - y cos(t) = 0 (quadratic
// convergence from the 4096-ulp float atan that Vulkan allows).
real atan2r(real y, real x) {
  if (y == R(0.0)) return x >= R(0.0) ? R(0.0) : PI_R;
  real t = real(atan(float(y), float(x)));
  for (int it = 0; it < 3; ++it) {
    real s, c;
    sincosr(t, s, c);
    t -= (x * s - y * c) / (x * c + y * s);
  }
  return t;
}
#endif

// acos(c) for c in [0, 1]; (1 - c)(1 + c) keeps the digits near c = 1.
real acosr(real c) { return atan2r(sqrt((R(1.0) - c) * (R(1.0) + c)), c); }

#endif
