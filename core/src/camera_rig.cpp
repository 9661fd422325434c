// CameraRig: poses, pairs, overlap and pair choice (the readers are rig.cpp's and
// calib_basalt.cpp's, beside their two-camera forms).
#include "curvestereo/camera_rig.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include "calib_common.hpp"

namespace cs {

namespace {

std::string camName(int k) { return "cam" + std::to_string(k); }

std::string percent(double share) { return calib::formatNumber(100.0 * share, 3) + " %"; }

// A camera's view: the rays within viewHalfAngle of its axis that land in its image.
bool inView(const BuiltCamera& cam, double cosHalfAngle, const Eigen::Vector3d& p) {
  const double norm = p.norm();
  if (!(norm > 0) || p.z() < cosHalfAngle * norm) return false;
  Vec2<double> px;
  return cam.project(p, px) && cam.inImage(px);
}

struct View {
  BuiltCamera cam;
  double cosHalfAngle;
  explicit View(const Camera& c) : cam(c), cosHalfAngle(std::cos(viewHalfAngle(c))) {}
  bool sees(const Eigen::Vector3d& p) const { return inView(cam, cosHalfAngle, p); }
};

// Depths (metres from camera i) at which pairOverlap tests a ray; 0 stands for infinity.
constexpr double kOverlapDepths[] = {1.0, 5.0, 0.0};

}  // namespace

Eigen::Vector3d CameraRig::centre() const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const BodyPose& pose : poses) sum += pose.p;
  return poses.empty() ? sum : Eigen::Vector3d(sum / double(poses.size()));
}

void CameraRig::validate() const {
  if (size() < 2) throw Error("a rig needs at least two cameras, it has " + std::to_string(size()));
  if (poses.size() != cameras.size())
    throw Error("a rig needs one pose per camera: " + std::to_string(cameras.size()) + " cameras, " +
                std::to_string(poses.size()) + " poses");
  for (int k = 0; k < size(); ++k) {
    calib::checkCamera(cameras[size_t(k)], camName(k));
    // The rotation's checks, with a stand-in translation (a camera may sit at the origin).
    calib::checkPose(poses[size_t(k)].R, Eigen::Vector3d::UnitX(), camName(k) + " pose");
    if (!poses[size_t(k)].p.allFinite()) throw Error(camName(k) + " pose has non-finite entries");
  }
  for (int i = 0; i < size(); ++i)
    for (int j = i + 1; j < size(); ++j) {
      const double baseline = (poses[size_t(i)].p - poses[size_t(j)].p).norm();
      if (baseline < 1e-6)
        throw Error(camName(i) + " and " + camName(j) + " sit at one centre (zero baseline, " +
                    calib::formatNumber(baseline, 3) + " m): no depth from them");
    }
  // A pair's share is the smaller of its two directions' overlaps, the same for (i, j) and
  // (j, i): each pair's computed once (the overlaps are most of a rig's validation).
  const size_t n = size_t(size());
  std::vector<double> shares(n * n, 0.0);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      shares[i * n + j] = shares[j * n + i] =
          std::min(pairOverlap(*this, int(i), int(j)), pairOverlap(*this, int(j), int(i)));
  for (int i = 0; i < size(); ++i) {
    double best = 0;
    int partner = -1;
    for (int j = 0; j < size(); ++j) {
      if (j == i) continue;
      const double share = shares[size_t(i) * n + size_t(j)];
      if (share > best) best = share, partner = j;
    }
    if (best < kMinOverlap)
      throw Error(camName(i) + " overlaps no other camera (the most: " +
                  (partner < 0 ? std::string("none") : camName(partner) + ", " + percent(best)) + "; at least " +
                  percent(kMinOverlap) + " is needed): check its pose");
  }
}

ImageWindow solvableWindow(const Rig& pair, const FieldOptions& options, int margin) {
  const BuiltCamera cam0(pair.cam0), cam1(pair.cam1);
  const int width = pair.cam0.width, height = pair.cam0.height;
  // Sampled every kStep px (and on the last row and column): the mask's outline is smooth
  // at that scale, and the margin covers what falls between the samples.
  constexpr int kStep = 4;
  margin = std::max(margin, kStep);
  int left = width, right = -1, top = height, bottom = -1;
  for (int y = 0; y < height; y = (y == height - 1) ? height : std::min(y + kStep, height - 1))
    for (int x = 0; x < width; x = (x == width - 1) ? width : std::min(x + kStep, width - 1)) {
      if (!fieldsAtPixel(cam0, cam1, pair.R, pair.t, options, x, y).valid) continue;
      left = std::min(left, x), right = std::max(right, x);
      top = std::min(top, y), bottom = std::max(bottom, y);
    }
  if (right < 0) return {};
  ImageWindow w;
  w.x0 = std::max(0, left - margin);
  w.y0 = std::max(0, top - margin);
  w.width = std::min(width - 1, right + margin) - w.x0 + 1;
  w.height = std::min(height - 1, bottom + margin) - w.y0 + 1;
  return w;
}

Rig pairRig(const CameraRig& rig, int i, int j) {
  if (i < 0 || j < 0 || i >= rig.size() || j >= rig.size() || i == j || rig.poses.size() != rig.cameras.size())
    throw Error("pairRig: cameras " + std::to_string(i) + " and " + std::to_string(j) +
                " are not two cameras of a rig of " + std::to_string(rig.size()));
  const BodyPose& a = rig.poses[size_t(i)];
  const BodyPose& b = rig.poses[size_t(j)];
  Rig pair;
  pair.cam0 = rig.cameras[size_t(i)];
  pair.cam1 = rig.cameras[size_t(j)];
  // X_body = Ra X_i + pa = Rb X_j + pb, so X_j = Rb^T Ra X_i + Rb^T (pa - pb).
  pair.R = b.R.transpose() * a.R;
  pair.t = b.R.transpose() * (a.p - b.p);
  return pair;
}

CameraRig rigFromPair(const Rig& pair) {
  CameraRig rig;
  rig.cameras = {pair.cam0, pair.cam1};
  // Camera 1's centre in camera 0's frame is -R^T t.
  rig.poses = {BodyPose{}, BodyPose{pair.R.transpose(), -pair.R.transpose() * pair.t}};
  return rig;
}

double viewHalfAngle(const Camera& cam) {
  const BuiltCamera built(cam);
  const double cx = cam.params[2], cy = cam.params[3];
  // The image circle reaches the nearest image edge along one of the four axis directions.
  const Vec2<double> edges[] = {{-0.5, cy}, {cam.width - 0.5, cy}, {cx, -0.5}, {cx, cam.height - 0.5}};
  double circle = std::numeric_limits<double>::infinity();
  for (const Vec2<double>& px : edges) {
    Vec3<double> ray;
    circle = std::min(circle, built.unproject(px, ray) ? std::acos(std::clamp(ray.z(), -1.0, 1.0)) : 0.0);
  }
  return std::min(std::max(circle, M_PI / 2), built.maxAngle());
}

RigViews::RigViews(const CameraRig& rig) : rig_(rig) {
  for (const Camera& cam : rig.cameras) {
    built_.emplace_back(cam);
    cosHalfAngle_.push_back(std::cos(viewHalfAngle(cam)));
  }
}

bool RigViews::seesInCamera(int k, const Eigen::Vector3d& p) const {
  return inView(built_[size_t(k)], cosHalfAngle_[size_t(k)], p);
}

bool RigViews::sees(int k, const Eigen::Vector3d& bodyPoint) const {
  const BodyPose& pose = rig_.poses[size_t(k)];
  return seesInCamera(k, pose.R.transpose() * (bodyPoint - pose.p));
}

int RigViews::seeing(const Eigen::Vector3d& bodyPoint) const {
  int n = 0;
  for (int k = 0; k < rig_.size(); ++k) n += sees(k, bodyPoint);
  return n;
}

int RigViews::seeingDirection(const Eigen::Vector3d& bodyDirection) const {
  int n = 0;
  for (int k = 0; k < rig_.size(); ++k) n += seesInCamera(k, rig_.poses[size_t(k)].R.transpose() * bodyDirection);
  return n;
}

double pairOverlap(const CameraRig& rig, int i, int j) {
  const Rig pair = pairRig(rig, i, j);
  const int step = std::max(1, std::max(pair.cam0.width, pair.cam0.height) / 128);
  const View from(pair.cam0), to(pair.cam1);
  long long inView = 0, seen = 0;
  for (int y = step / 2; y < pair.cam0.height; y += step)
    for (int x = step / 2; x < pair.cam0.width; x += step) {
      Vec3<double> ray;
      if (!from.cam.unproject(Vec2<double>(x, y), ray) || !from.sees(ray)) continue;
      ++inView;
      for (double depth : kOverlapDepths) {
        const Eigen::Vector3d p = depth > 0 ? Eigen::Vector3d(pair.R * (depth * ray) + pair.t) : pair.R * ray;
        seen += to.sees(p);
      }
    }
  return inView ? double(seen) / double(inView * std::size(kOverlapDepths)) : 0.0;
}

std::vector<PairInfo> pairTable(const CameraRig& rig) {
  std::vector<PairInfo> table;
  for (int i = 0; i < rig.size(); ++i)
    for (int j = i + 1; j < rig.size(); ++j)
      table.push_back({i, j, pairOverlap(rig, i, j), pairOverlap(rig, j, i),
                       (rig.poses[size_t(i)].p - rig.poses[size_t(j)].p).norm()});
  return table;
}

namespace {

bool usable(const PairInfo& p) { return std::min(p.overlapIJ, p.overlapJI) >= kMinOverlap; }

// Overlap gives the share of pixels that can get a depth, the baseline how precise it is.
double score(const PairInfo& p) { return std::min(p.overlapIJ, p.overlapJI) * p.baseline; }

}  // namespace

std::vector<PairInfo> choosePairs(const CameraRig& rig, int partners) {
  const std::vector<PairInfo> table = pairTable(rig);
  std::set<std::pair<int, int>> chosen;
  for (int k = 0; k < rig.size(); ++k) {
    std::vector<const PairInfo*> mine;
    for (const PairInfo& p : table)
      if ((p.i == k || p.j == k) && usable(p)) mine.push_back(&p);
    std::stable_sort(mine.begin(), mine.end(), [](auto* a, auto* b) { return score(*a) > score(*b); });
    for (size_t n = 0; n < mine.size() && int(n) < partners; ++n) chosen.insert({mine[n]->i, mine[n]->j});
  }
  std::vector<PairInfo> pairs;
  for (const PairInfo& p : table)
    if (chosen.count({p.i, p.j})) pairs.push_back(p);
  return pairs;
}

std::vector<PairInfo> parsePairs(const CameraRig& rig, const std::string& text) {
  const std::string usage = "--pairs expects I-J[,I-J...] (camera indexes, e.g. 0-1,1-2), got '" + text + "'";
  std::vector<PairInfo> pairs;
  std::set<std::pair<int, int>> seen;
  std::stringstream list(text);
  std::string item;
  while (std::getline(list, item, ',')) {
    int i = -1, j = -1;
    char dash = 0, rest = 0;
    std::istringstream is(item);
    if (!(is >> i >> dash >> j) || dash != '-' || (is >> rest)) throw Error(usage);
    if (i < 0 || j < 0 || i >= rig.size() || j >= rig.size() || i == j)
      throw Error("--pairs: " + item + " is not two cameras of this rig (cam0 to " + camName(rig.size() - 1) + ")");
    if (!seen.insert({std::min(i, j), std::max(i, j)}).second) throw Error("--pairs: " + item + " is given twice");
    const Rig pair = pairRig(rig, i, j);
    PairInfo p{i, j, pairOverlap(rig, i, j), pairOverlap(rig, j, i), pair.t.norm()};
    if (!usable(p))
      throw Error("--pairs: " + camName(i) + " and " + camName(j) + " overlap too little (" +
                  percent(std::min(p.overlapIJ, p.overlapJI)) + "; at least " + percent(kMinOverlap) + ")");
    pairs.push_back(p);
  }
  if (pairs.empty()) throw Error(usage);
  return pairs;
}

CameraRig parseCameraRig(const std::string& text, const std::string& name) {
  const CalibFormat format = detectCalibFormat(text, name);
  if (format == CalibFormat::Kalibr) return parseKalibrRig(text, name);
  if (format == CalibFormat::Basalt) return parseBasaltRig(text, name);
  // The pair formats make a rig of their two cameras.
  CameraRig rig = rigFromPair(parseCalibration(text, name));
  calib::checkCameraRig(rig, name);
  return rig;
}

CameraRig loadCameraRig(const std::string& path) { return parseCameraRig(calib::readTextFile(path), path); }

}  // namespace cs
