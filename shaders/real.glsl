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

// atan2(y, x) for y >= 0 (every use here): a float estimate refined by Newton steps on
// x sin(t) - y cos(t) = 0 (quadratic convergence; three steps reach double precision
// from the 4096-ulp float atan that Vulkan allows).
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

// acos(c) for c in [0, 1]; (1 - c)(1 + c) keeps the digits near c = 1.
real acosr(real c) { return atan2r(sqrt((R(1.0) - c) * (R(1.0) + c)), c); }

#endif
