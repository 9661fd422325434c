// A Backend that forwards every fine kernel and every memory operation to another one and
// keeps Backend's default coarse kernels (their documented sequences of fine kernels).
// Test wrappers derive from it and override what they observe or change.
#pragma once
#include <string>

#include "curvestereo/backend.hpp"

namespace cs::test {

class ForwardingBackend : public Backend {
 public:
  explicit ForwardingBackend(Backend& inner) : b_(inner) {}
  std::string name() const override { return b_.name(); }
  std::string device() const override { return b_.device(); }
  void synchronize() override { b_.synchronize(); }

 protected:
  Buffer doCreate(int w, int h, int c) override { return b_.create(w, h, c); }
  void doUpload(const Buffer& d, const float* h, bool* f) override { b_.upload(d, h, f); }
  void doUploadBytes(const Buffer& d, const uint8_t* h) override { b_.uploadBytes(d, h); }
  void doDownload(const Buffer& s, float* h) override { b_.download(s, h); }
  void doDownloadAll(const std::vector<Download>& d) override { b_.downloadAll(d); }
  void doFill(const Buffer& d, float v) override { b_.fill(d, v); }
  void doCopy(const Buffer& d, const Buffer& s) override { b_.copy(d, s); }
  void doFields(const Buffer& m, const Buffer& c, const Buffer& t, const FieldsParams& p) override {
    b_.fields(m, c, t, p);
  }
  void doWarp(const Buffer& d, const Buffer& s, const Buffer& f) override { b_.warp(d, s, f); }
  void doDownsample(const Buffer& d, const Buffer& s, float sc) override { b_.downsample(d, s, sc); }
  void doUpsample(const Buffer& d, const Buffer& s, float sc, float v) override { b_.upsample(d, s, sc, v); }
  void doUpsampleEstimate(const Buffer& u, const Buffer& w, const Buffer& cu, const Buffer& cw, const Buffer& n0,
                          const Buffer& n1, const Buffer& m, const EstimateUpsampleParams& p) override {
    b_.upsampleEstimate(u, w, cu, cw, n0, n1, m, p);
  }
  void doNormalise(const Buffer& d, const Buffer& mo, const Buffer& s, const Buffer& m,
                   const NormaliseParams& p) override {
    b_.normalise(d, mo, s, m, p);
  }
  void doStructureTensor(const Buffer& t, const Buffer& s, const Buffer& i, const Buffer& m,
                         const TensorParams& p) override {
    b_.structureTensor(t, s, i, m, p);
  }
  void doWarpDerivatives(const DataTermBuffers& d, const Buffer& t, const Buffer& i0, const Buffer& i1,
                         const Buffer& tr, const Buffer& w, const Buffer& u, const Buffer& m, const Buffer& c,
                         float floor) override {
    b_.warpDerivatives(d, t, i0, i1, tr, w, u, m, c, floor);
  }
  void doPrimalDual(const PrimalDualBuffers& pd, const DataTermBuffers& d, const Buffer& t, const Buffer& s,
                    const Buffer& m, const PrimalDualParams& p) override {
    b_.primalDual(pd, d, t, s, m, p);
  }
  void doMedian(const Buffer& d, const Buffer& s, const Buffer& m) override { b_.median(d, s, m); }
  void doAccumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& t, const Buffer& m,
                    float d) override {
    b_.accumulate(u, w, u0, t, m, d);
  }
  void doSweepWarp(const Buffer& v, const Buffer& i, const Buffer& m, const SweepParams& p) override {
    b_.sweepWarp(v, i, m, p);
  }
  void doSweepCost(const Buffer& c, const Buffer& r, const Buffer& v, const Buffer& m, const SweepParams& p) override {
    b_.sweepCost(c, r, v, m, p);
  }
  void doSweepAggregate(const Buffer& a, const Buffer& c, const Buffer& m, const SweepParams& p) override {
    b_.sweepAggregate(a, c, m, p);
  }
  void doSweepSelect(const Buffer& b, const Buffer& a, const Buffer& c, const Buffer& m,
                     const SweepParams& p) override {
    b_.sweepSelect(b, a, c, m, p);
  }
  void doSweepInitialise(const Buffer& u, const Buffer& w, const Buffer& c, const Buffer& b, const Buffer& o,
                         const Buffer& m, const SweepParams& p, const ConsistencyParams& cp) override {
    b_.sweepInitialise(u, w, c, b, o, m, p, cp);
  }
  void doSweepBandWarp(const Buffer& v, const Buffer& f, const Buffer& i, const Buffer& cb, const Buffer& m,
                       const SweepParams& p, float s) override {
    b_.sweepBandWarp(v, f, i, cb, m, p, s);
  }
  void doSweepBandCost(const Buffer& c, const Buffer& r, const Buffer& v, const Buffer& f, const Buffer& m,
                       const SweepParams& p) override {
    b_.sweepBandCost(c, r, v, f, m, p);
  }
  void doSweepBandAggregate(const Buffer& a, const Buffer& c, const Buffer& f, const Buffer& m,
                            const SweepParams& p) override {
    b_.sweepBandAggregate(a, c, f, m, p);
  }
  void doSweepBandSelect(const Buffer& b, const Buffer& a, const Buffer& c, const Buffer& f, const Buffer& m,
                         const SweepParams& p) override {
    b_.sweepBandSelect(b, a, c, f, m, p);
  }
  void doTriangulate(const Buffer& r, const Buffer& p, const Buffer& w, const Buffer& m, const CameraParams& c,
                     const double t[3]) override {
    b_.triangulate(r, p, w, m, c, t);
  }
  void doCarryEstimate(const Buffer& d, const Buffer& s, const Buffer& g, const Buffer& mo, const Buffer& m,
                       const CarryParams& p) override {
    b_.carryEstimate(d, s, g, mo, m, p);
  }
  void doTemporalFilter(const Buffer& st, const Buffer& u, const Buffer& w, const Buffer& pr, const Buffer& r,
                        const Buffer& pt, const Buffer& c, const Buffer& m, const TemporalParams& p) override {
    b_.temporalFilter(st, u, w, pr, r, pt, c, m, p);
  }
  void doFinishResult(const Buffer& v, const Buffer& z, const Buffer& r, const Buffer& pt, const Buffer& u,
                      const Buffer& w, const Buffer& c) override {
    b_.finishResult(v, z, r, pt, u, w, c);
  }
  void doPlainSupport(const Buffer& s, const Buffer& c, const Buffer& w, const Buffer& m, const Buffer& li,
                      const Buffer& lm) override {
    b_.plainSupport(s, c, w, m, li, lm);
  }
  void doFillPlanes(const Buffer& u, const Buffer& w, const Buffer& pc, const Buffer& l, const Buffer& p,
                    const Buffer& m, const CameraParams& cam, const double t[3]) override {
    b_.fillPlanes(u, w, pc, l, p, m, cam, t);
  }
  void doPanoramaPlace(const Buffer& place, const Buffer& radial, const Buffer& rays,
                       const PanoramaParams& p) override {
    b_.panoramaPlace(place, radial, rays, p);
  }
  void doPanoramaSplat(const Buffer& a, const Buffer& place, const Buffer& c, const Buffer& g,
                       const PanoramaParams& p) override {
    b_.panoramaSplat(a, place, c, g, p);
  }
  void doPanoramaResolve(const Buffer& r, const Buffer& g, const Buffer& c, const Buffer& a) override {
    b_.panoramaResolve(r, g, c, a);
  }
  void doRoundTrip(const Buffer& e, const Buffer& w, const Buffer& c, const Buffer& rw, const Buffer& rc,
                   const Buffer& rm, const Buffer& m) override {
    b_.roundTrip(e, w, c, rw, rc, rm, m);
  }
  void doResultConfidence(const Buffer& c, const Buffer& r, const Buffer& pt, const Buffer& i, const Buffer& n0,
                          const Buffer& n1, const Buffer& w, const Buffer& t, const Buffer& sc, const Buffer& e,
                          const Buffer& pc, const Buffer& m, const ConfidenceParams& p) override {
    b_.resultConfidence(c, r, pt, i, n0, n1, w, t, sc, e, pc, m, p);
  }

 protected:
  Backend& b_;
};

}  // namespace cs::test
