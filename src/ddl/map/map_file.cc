// Layout of a map file (little-endian, version 2; docs/map-files.md; version 1 ends after the map
// points):
//   header, 96 bytes:
//     0  char[8] magic "DDLSMAP\0"      8  u32 version          12 u32 reserved (0)
//    16  u64 descriptor tag            24  u64 vocabulary words
//    32  u32 image width               36  u32 image height
//    40  f64 fx  48 f64 fy  56 f64 cx  64 f64 cy
//    72  u64 origin keyframe id        80  u64 keyframe count   88 u64 map point count
//   keyframe, in id order (the origin first):
//     u64 id, f64 timestamp, f64[4] quaternion x y z w (T_c_w), f64[3] translation,
//     i64 parent id (-1: none), u32 loop edge count, u64[] loop edge ids,
//     u32 pyramid levels, f64 scale factor, u32 feature count N,
//     N x (f32 x, y, size, angle, response, i32 octave), N x u8[32] descriptor,
//     N x f32 depth (0: none), N x f32 u_right (< 0: none),
//     u32 byte count and a 16-bit PNG of the depth image at 5000 per metre (0 bytes: none),
//     u32 byte count and an 8-bit PNG of the dynamic mask (0 bytes: none)
//   map point, in id order:
//     u64 id, u64 reference keyframe id, f64[3] position, i32 visible, i32 found,
//     u32 observation count, observations x (u64 keyframe id, u32 feature index, u8 stereo)
//   dense scans (version 2): u64 count, then each:
//     u64 anchor keyframe id, f64[4] quaternion x y z w and f64[3] translation of T_anchor_c,
//     u32 pixel step s, then PNGs of ceil(width / s) x ceil(height / s) pixels, each after its u32
//     byte count: 8-bit colour (BGR), 16-bit depth at 5000 per metre, 8-bit exclusion mask (0
//     bytes: none)
//   zero padding to a multiple of 8, u64 checksum of every preceding byte.

#include "ddl/map/map_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <vector>

#include "ddl/core/binary_file.h"
#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"

namespace ddl::map {
namespace {

constexpr char kMagic[8] = {'D', 'D', 'L', 'S', 'M', 'A', 'P', '\0'};
constexpr std::uint32_t kVersion = 2;
constexpr std::uint32_t kOldestVersion = 1;  // without dense scans
constexpr int kMaxPixelStep = 64;
constexpr std::size_t kHeaderBytes = 96;
constexpr std::size_t kChecksumBytes = 8;
constexpr std::size_t kDescriptorBytes = 32;
constexpr std::int64_t kNoParent = -1;
constexpr std::uint32_t kMaxLevels = 32;
constexpr double kDepthUnitsPerMetre = 5000.0;  // TUM's depth PNGs
// Bounds that no real map reaches, so that a damaged file that passes the checksum cannot ask for
// absurd memory: ids stay far from overflow, a keyframe was tracked with at least 30 matches
// (tracking.matching.local_map_min_inliers), and a point's representative descriptor compares all
// its observations pairwise.
constexpr std::uint64_t kMaxId = std::uint64_t{1} << 62;
constexpr std::size_t kMinFeatures = 10;
constexpr std::size_t kMaxObservations = 4096;

class Writer {
 public:
  template <typename T>
  void put(T value) {
    const auto* p = reinterpret_cast<const unsigned char*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void put_bytes(const unsigned char* p, std::size_t n) { bytes_.insert(bytes_.end(), p, p + n); }
  std::vector<unsigned char>& bytes() { return bytes_; }

 private:
  std::vector<unsigned char> bytes_;
};

/// Reads the payload; running past its end throws with the record being read.
class Reader {
 public:
  Reader(const std::string& path, const unsigned char* data, std::size_t size)
      : path_(path), data_(data), size_(size) {}

  void set_record(std::string record) { record_ = std::move(record); }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError::at(path_, record_.empty() ? what : fmt::format("{}: {}", record_, what));
  }
  void need(std::size_t n) const {
    if (n > size_ - offset_) fail(fmt::format("truncated at byte {} of {}", offset_, size_));
  }
  template <typename T>
  T get() {
    need(sizeof(T));
    T value;
    std::memcpy(&value, data_ + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  const unsigned char* take(std::size_t n) {
    need(n);
    const unsigned char* p = data_ + offset_;
    offset_ += n;
    return p;
  }
  /// A count of records of at least `record_bytes` each, checked against what is left.
  std::size_t count(std::uint64_t n, std::size_t record_bytes, const char* what) const {
    if (n > (size_ - offset_) / record_bytes) {
      fail(fmt::format("{} {} cannot fit in the {} bytes left", n, what, size_ - offset_));
    }
    return static_cast<std::size_t>(n);
  }
  std::size_t offset() const { return offset_; }

 private:
  const std::string& path_;
  const unsigned char* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
  std::string record_;
};

void write_png(Writer& w, const cv::Mat& image) {
  std::vector<unsigned char> png;
  if (!image.empty() && !cv::imencode(".png", image, png)) png.clear();
  w.put<std::uint32_t>(static_cast<std::uint32_t>(png.size()));
  w.put_bytes(png.data(), png.size());
}

/// The images of a dense scan at `pixel_step` (OctreeMap's subsampling: every step-th pixel from
/// the first).
cv::Size scan_size(const MapFileInfo& info, int pixel_step) {
  return {(info.image_width + pixel_step - 1) / pixel_step,
          (info.image_height + pixel_step - 1) / pixel_step};
}

/// Metres to TUM's 16-bit units; beyond 13.1 m, negative and non-finite become no measurement.
cv::Mat depth_units_of(const cv::Mat& depth_m) {
  cv::Mat depth = depth_m.clone();
  depth.setTo(0.0f, ~(depth == depth) | (depth > 65535.0 / kDepthUnitsPerMetre) | (depth < 0.0f));
  cv::Mat units;
  depth.convertTo(units, CV_16UC1, kDepthUnitsPerMetre);
  return units;
}

void put_pose(Writer& w, const SE3& T) {
  const Quatd& q = T.quaternion();
  for (double v : {q.x(), q.y(), q.z(), q.w()}) w.put<double>(v);
  for (int i = 0; i < 3; ++i) w.put<double>(T.translation()[i]);
}

/// A pose as put_pose() wrote it; fails on a non-finite value or a quaternion whose norm is not 1.
SE3 get_pose(Reader& r, const char* what) {
  double q[4];
  for (double& v : q) v = r.get<double>();
  Vec3d t;
  for (int i = 0; i < 3; ++i) t[i] = r.get<double>();
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!t.allFinite() || !(std::abs(norm - 1.0) < 1e-6)) {
    r.fail(fmt::format("invalid {} (the quaternion must have norm 1)", what));
  }
  return SE3(Quatd(q[3], q[0], q[1], q[2]), t);
}

void write_images(Writer& w, const std::optional<KeyFrameImages>& images, const MapFileInfo& info) {
  const cv::Size size(info.image_width, info.image_height);
  cv::Mat depth_units;
  cv::Mat mask;
  if (images && images->depth_m.type() == CV_32FC1 && images->depth_m.size() == size) {
    depth_units = depth_units_of(images->depth_m);  // rounded to TUM's unit
    if (images->dynamic_mask.type() == CV_8UC1 && images->dynamic_mask.size() == size &&
        cv::countNonZero(images->dynamic_mask) > 0) {
      mask = images->dynamic_mask != 0;
    }
  }
  write_png(w, depth_units);
  write_png(w, mask);
}

void write_keyframe(Writer& w, const KeyFrame& kf, const std::set<KeyFrameId>& stored,
                    const KeyFrameImagesFn& images, const MapFileInfo& info) {
  w.put<std::uint64_t>(kf.id());
  w.put<double>(kf.timestamp_s());
  put_pose(w, kf.T_c_w());
  const KeyFramePtr parent = kf.parent();
  w.put<std::int64_t>(parent && stored.count(parent->id()) > 0
                          ? static_cast<std::int64_t>(parent->id())
                          : kNoParent);
  std::vector<KeyFrameId> loops;
  for (const KeyFramePtr& other : kf.loop_edges()) {
    if (stored.count(other->id()) > 0) loops.push_back(other->id());
  }
  w.put<std::uint32_t>(static_cast<std::uint32_t>(loops.size()));
  for (KeyFrameId id : loops) w.put<std::uint64_t>(id);

  const FrameFeatures& f = kf.features();
  w.put<std::uint32_t>(static_cast<std::uint32_t>(f.pyramid.num_levels));
  w.put<double>(f.pyramid.scale_factor);
  const std::size_t n = f.size();
  w.put<std::uint32_t>(static_cast<std::uint32_t>(n));
  for (const cv::KeyPoint& k : f.keypoints) {
    for (float v : {k.pt.x, k.pt.y, k.size, k.angle, k.response}) w.put<float>(v);
    w.put<std::int32_t>(k.octave);
  }
  for (std::size_t i = 0; i < n; ++i)
    w.put_bytes(f.descriptors.ptr(static_cast<int>(i)), kDescriptorBytes);
  for (std::size_t i = 0; i < n; ++i) w.put<float>(f.depth_m[i]);
  for (std::size_t i = 0; i < n; ++i) w.put<float>(f.u_right.empty() ? -1.0f : f.u_right[i]);
  write_images(w, images ? images(kf.id()) : std::nullopt, info);
}

struct PointRecord {
  MapPointId id = 0;
  KeyFrameId reference_id = 0;
  Vec3d p_w = Vec3d::Zero();
  int visible = 1;
  int found = 1;
  struct Obs {
    KeyFrameId keyframe_id;
    std::uint32_t feature_index;
    bool stereo;
  };
  std::vector<Obs> observations;
};

std::shared_ptr<FrameFeatures> read_features(Reader& r, const MapFileInfo& info) {
  const auto levels = r.get<std::uint32_t>();
  const auto scale_factor = r.get<double>();
  if (levels < 1 || levels > kMaxLevels) {
    r.fail(fmt::format("{} pyramid levels (1..{} expected)", levels, kMaxLevels));
  }
  if (!(scale_factor > 1.0 && scale_factor < 4.0)) {
    r.fail(fmt::format("pyramid scale factor {} (between 1 and 4 expected)", scale_factor));
  }
  constexpr std::size_t kFeatureBytes = 24 + kDescriptorBytes + 8;
  const std::size_t n = r.count(r.get<std::uint32_t>(), kFeatureBytes, "features");
  if (n < kMinFeatures)
    r.fail(fmt::format("{} features (a keyframe has at least {})", n, kMinFeatures));
  auto f = std::make_shared<FrameFeatures>();
  f->pyramid = features::make_scale_pyramid(static_cast<int>(levels), scale_factor);
  f->keypoints.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    cv::KeyPoint& k = f->keypoints[i];
    k.pt.x = r.get<float>();
    k.pt.y = r.get<float>();
    k.size = r.get<float>();
    k.angle = r.get<float>();
    k.response = r.get<float>();
    k.octave = r.get<std::int32_t>();
    if (!std::isfinite(k.pt.x) || !std::isfinite(k.pt.y) || !std::isfinite(k.size) ||
        !std::isfinite(k.angle) || !std::isfinite(k.response)) {
      r.fail(fmt::format("feature {} has a non-finite position, size, angle or response", i));
    }
    if (k.octave < 0 || k.octave >= static_cast<int>(levels)) {
      r.fail(fmt::format("feature {} is on pyramid level {} of {}", i, k.octave, levels));
    }
  }
  f->descriptors.create(static_cast<int>(n), static_cast<int>(kDescriptorBytes), CV_8U);
  for (std::size_t i = 0; i < n; ++i) {
    std::memcpy(f->descriptors.ptr(static_cast<int>(i)), r.take(kDescriptorBytes),
                kDescriptorBytes);
  }
  f->depth_m.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    f->depth_m[i] = r.get<float>();
    if (!(f->depth_m[i] >= 0.0f) || !std::isfinite(f->depth_m[i])) {
      r.fail(fmt::format("feature {} has depth {}", i, f->depth_m[i]));
    }
  }
  f->u_right.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    f->u_right[i] = r.get<float>();
    if (!std::isfinite(f->u_right[i]))
      r.fail(fmt::format("feature {} has u_right {}", i, f->u_right[i]));
  }
  f->grid = features::FeatureGrid(f->keypoints,
                                  cv::Rect2f(0.0f, 0.0f, static_cast<float>(info.image_width),
                                             static_cast<float>(info.image_height)));
  return f;
}

/// The image of a PNG block (empty for 0 bytes); `type` and `size` are what it must decode to.
cv::Mat read_png(Reader& r, cv::Size size, int type, const char* what) {
  const std::size_t bytes = r.count(r.get<std::uint32_t>(), 1, what);
  if (bytes == 0) return {};
  const unsigned char* data = r.take(bytes);
  const cv::Mat encoded(1, static_cast<int>(bytes), CV_8UC1, const_cast<unsigned char*>(data));
  cv::Mat image = cv::imdecode(encoded, cv::IMREAD_UNCHANGED);
  if (image.empty() || image.type() != type || image.size() != size) {
    r.fail(fmt::format("its {} is not a {}x{} {} PNG", what, size.width, size.height,
                       type == CV_16UC1  ? "16-bit"
                       : type == CV_8UC3 ? "8-bit colour"
                                         : "8-bit"));
  }
  return image;
}

cv::Mat read_png(Reader& r, const MapFileInfo& info, int type, const char* what) {
  return read_png(r, cv::Size(info.image_width, info.image_height), type, what);
}

void write_dense_scan(Writer& w, const DenseScan& scan, const MapFileInfo& info) {
  const auto bad = [&](const std::string& what) {
    return Error(
        fmt::format("map file: dense scan anchored to keyframe {}: {}", scan.anchor, what));
  };
  if (scan.pixel_step < 1 || scan.pixel_step > kMaxPixelStep) {
    throw bad(fmt::format("pixel step {} (1..{})", scan.pixel_step, kMaxPixelStep));
  }
  const cv::Size size = scan_size(info, scan.pixel_step);
  if (scan.bgr.type() != CV_8UC3 || scan.bgr.size() != size || scan.depth_m.type() != CV_32FC1 ||
      scan.depth_m.size() != size ||
      (!scan.exclude.empty() && (scan.exclude.type() != CV_8UC1 || scan.exclude.size() != size))) {
    throw bad(fmt::format("its images are not colour, depth and mask of {}x{} pixels", size.width,
                          size.height));
  }
  w.put<std::uint64_t>(scan.anchor);
  put_pose(w, scan.T_anchor_c);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(scan.pixel_step));
  write_png(w, scan.bgr);
  write_png(w, depth_units_of(scan.depth_m));
  write_png(w, scan.exclude.empty() || cv::countNonZero(scan.exclude) == 0
                   ? cv::Mat()
                   : cv::Mat(scan.exclude != 0));
}

}  // namespace

void save_map_file(const Map& map, const MapFileInfo& info, const std::string& path,
                   const KeyFrameImagesFn& images, const std::vector<DenseScan>& dense_scans) {
  // The keyframes of the spanning tree: the origin and those whose parent chain reaches it.
  // Left out are keyframes local mapping never took in (no parent yet: still queued when a worker
  // failed), with whatever hangs below them.
  std::vector<KeyFramePtr> candidates = map.keyframes();
  std::set<KeyFrameId> stored;
  for (const KeyFramePtr& kf : candidates) {
    if (kf->is_origin()) stored.insert(kf->id());
  }
  for (bool grew = true; grew;) {
    grew = false;
    for (const KeyFramePtr& kf : candidates) {
      const KeyFramePtr parent = kf->parent();
      if (stored.count(kf->id()) == 0 && parent && stored.count(parent->id()) > 0) {
        stored.insert(kf->id());
        grew = true;
      }
    }
  }
  std::vector<KeyFramePtr> keyframes;
  for (const KeyFramePtr& kf : candidates) {
    if (stored.count(kf->id()) > 0) keyframes.push_back(kf);
  }
  // The origin first (the lowest id): the loader's map makes its first keyframe the origin.
  std::stable_partition(keyframes.begin(), keyframes.end(),
                        [](const KeyFramePtr& kf) { return kf->is_origin(); });
  const std::vector<MapPointPtr> points = map.map_points();

  Writer w;
  w.put_bytes(reinterpret_cast<const unsigned char*>(kMagic), sizeof(kMagic));
  w.put<std::uint32_t>(kVersion);
  w.put<std::uint32_t>(0);
  w.put<std::uint64_t>(info.descriptor_tag);
  w.put<std::uint64_t>(info.vocabulary_words);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(info.image_width));
  w.put<std::uint32_t>(static_cast<std::uint32_t>(info.image_height));
  for (double v : {info.fx, info.fy, info.cx, info.cy}) w.put<double>(v);
  w.put<std::uint64_t>(keyframes.empty() ? 0 : keyframes.front()->id());
  w.put<std::uint64_t>(keyframes.size());
  // The point count is known once the points without a stored observation are left out.
  const std::size_t point_count_at = w.bytes().size();
  w.put<std::uint64_t>(0);
  for (const KeyFramePtr& kf : keyframes) write_keyframe(w, *kf, stored, images, info);

  std::uint64_t point_count = 0;
  for (const MapPointPtr& p : points) {
    std::vector<MapPoint::Observation> observations;
    for (MapPoint::Observation& obs : p->observations()) {
      if (stored.count(obs.keyframe->id()) > 0) observations.push_back(std::move(obs));
    }
    if (observations.empty()) continue;
    const KeyFramePtr reference = p->reference_keyframe();
    w.put<std::uint64_t>(p->id());
    const bool reference_observes =
        reference && std::any_of(observations.begin(), observations.end(),
                                 [&](const MapPoint::Observation& obs) {
                                   return obs.keyframe->id() == reference->id();
                                 });
    w.put<std::uint64_t>(reference_observes ? reference->id()
                                            : observations.front().keyframe->id());
    const Vec3d p_w = p->position_w();
    for (int i = 0; i < 3; ++i) w.put<double>(p_w[i]);
    w.put<std::int32_t>(p->visible_count());
    w.put<std::int32_t>(p->found_count());
    w.put<std::uint32_t>(static_cast<std::uint32_t>(observations.size()));
    for (const MapPoint::Observation& obs : observations) {
      w.put<std::uint64_t>(obs.keyframe->id());
      w.put<std::uint32_t>(static_cast<std::uint32_t>(obs.feature_index));
      w.put<std::uint8_t>(obs.stereo ? 1 : 0);
    }
    ++point_count;
  }
  std::memcpy(w.bytes().data() + point_count_at, &point_count, sizeof(point_count));
  std::vector<const DenseScan*> scans;
  for (const DenseScan& scan : dense_scans) {
    if (stored.count(scan.anchor) > 0) scans.push_back(&scan);
  }
  w.put<std::uint64_t>(scans.size());
  for (const DenseScan* scan : scans) write_dense_scan(w, *scan, info);
  while (w.bytes().size() % 8 != 0) w.put<std::uint8_t>(0);
  w.put<std::uint64_t>(checksum64(w.bytes().data(), w.bytes().size()));
  write_file_atomically(
      path, "the sparse map",
      std::string_view(reinterpret_cast<const char*>(w.bytes().data()), w.bytes().size()));
}

MapFileContents load_map_file(const std::string& path, Map& map,
                              const std::function<void(const MapFileInfo&)>& accept) {
  if (map.keyframe_count() != 0 || map.map_point_count() != 0) {
    throw Error(fmt::format("{}: a map file is loaded into an empty map only", path));
  }
  const MappedFile bytes(path);
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throw InputError::at(path, "not a DDL-SLAM map file (wrong magic; expected \"DDLSMAP\")");
  }
  if (bytes.size() < kHeaderBytes + kChecksumBytes || bytes.size() % 8 != 0) {
    throw InputError::at(path, fmt::format("truncated or padded wrongly: {} bytes", bytes.size()));
  }
  std::uint32_t version;
  std::memcpy(&version, bytes.data() + 8, sizeof(version));
  if (version < kOldestVersion || version > kVersion) {
    throw InputError::at(path, fmt::format("unsupported map file version {} (this build reads "
                                           "versions {} to {})",
                                           version, kOldestVersion, kVersion));
  }
  const std::size_t payload = bytes.size() - kChecksumBytes;
  std::uint64_t stored_checksum;
  std::memcpy(&stored_checksum, bytes.data() + payload, sizeof(stored_checksum));
  if (checksum64(bytes.data(), payload) != stored_checksum) {
    throw InputError::at(path, "checksum mismatch: the file is corrupted or truncated");
  }

  Reader r(path, bytes.data(), payload);
  r.take(sizeof(kMagic) + 8);
  MapFileContents contents;
  contents.version = version;
  MapFileInfo& info = contents.info;
  info.descriptor_tag = r.get<std::uint64_t>();
  info.vocabulary_words = r.get<std::uint64_t>();
  info.image_width = static_cast<int>(r.get<std::uint32_t>());
  info.image_height = static_cast<int>(r.get<std::uint32_t>());
  info.fx = r.get<double>();
  info.fy = r.get<double>();
  info.cx = r.get<double>();
  info.cy = r.get<double>();
  if (info.image_width <= 0 || info.image_height <= 0 || info.image_width > 100000 ||
      info.image_height > 100000 || !(info.fx > 0.0) || !(info.fy > 0.0)) {
    r.fail(fmt::format("invalid camera in the header ({}x{}, fx {}, fy {})", info.image_width,
                       info.image_height, info.fx, info.fy));
  }
  if (accept) accept(info);
  const auto origin_id = r.get<std::uint64_t>();
  constexpr std::size_t kMinKeyFrameBytes = 8 + 8 + 56 + 8 + 4 + 4 + 8 + 4 + 8;
  constexpr std::size_t kMinPointBytes = 8 + 8 + 24 + 4 + 4 + 4;
  const std::size_t keyframe_count =
      r.count(r.get<std::uint64_t>(), kMinKeyFrameBytes, "keyframes");
  const std::uint64_t point_count = r.get<std::uint64_t>();

  std::map<KeyFrameId, KeyFramePtr> keyframes;
  std::map<KeyFrameId, std::int64_t> parents;
  std::map<KeyFrameId, std::vector<KeyFrameId>> loop_edges;
  std::vector<KeyFramePtr> order;
  KeyFrameId next_keyframe_id = 0;
  for (std::size_t k = 0; k < keyframe_count; ++k) {
    r.set_record(fmt::format("keyframe {} of {}", k + 1, keyframe_count));
    const auto id = r.get<std::uint64_t>();
    r.set_record(fmt::format("keyframe {} of {} (id {})", k + 1, keyframe_count, id));
    if (id >= kMaxId) r.fail("id out of range");
    if (keyframes.count(id) > 0) r.fail("duplicate keyframe id");
    if (k > 0 && id <= origin_id) r.fail(fmt::format("id below the origin's, {}", origin_id));
    if (k == 0 && id != origin_id) {
      r.fail(fmt::format("the first keyframe must be the origin, id {}", origin_id));
    }
    const auto timestamp_s = r.get<double>();
    if (!std::isfinite(timestamp_s)) r.fail("invalid timestamp");
    const SE3 T_c_w = get_pose(r, "pose");
    parents[id] = r.get<std::int64_t>();
    const std::size_t loops = r.count(r.get<std::uint32_t>(), 8, "loop edges");
    for (std::size_t i = 0; i < loops; ++i) loop_edges[id].push_back(r.get<std::uint64_t>());
    std::shared_ptr<FrameFeatures> features = read_features(r, info);
    const cv::Mat depth_units = read_png(r, info, CV_16UC1, "depth image");
    const cv::Mat mask = read_png(r, info, CV_8UC1, "dynamic mask");
    if (!depth_units.empty()) {
      KeyFrameImages& images = contents.images[id];
      depth_units.convertTo(images.depth_m, CV_32FC1, 1.0 / kDepthUnitsPerMetre);
      images.dynamic_mask = mask;
    }
    auto kf = std::make_shared<KeyFrame>(id, timestamp_s, std::move(features), T_c_w);
    keyframes[id] = kf;
    order.push_back(kf);
    next_keyframe_id = std::max(next_keyframe_id, id + 1);
  }

  std::vector<PointRecord> records;
  const std::size_t points = r.count(point_count, kMinPointBytes, "map points");
  records.reserve(points);
  std::set<MapPointId> point_ids;
  std::set<std::pair<KeyFrameId, std::uint32_t>> used_slots;  // one point per feature
  MapPointId next_point_id = 0;
  for (std::size_t k = 0; k < points; ++k) {
    r.set_record(fmt::format("map point {} of {}", k + 1, points));
    PointRecord p;
    p.id = r.get<std::uint64_t>();
    r.set_record(fmt::format("map point {} of {} (id {})", k + 1, points, p.id));
    if (p.id >= kMaxId) r.fail("id out of range");
    if (!point_ids.insert(p.id).second) r.fail("duplicate map point id");
    p.reference_id = r.get<std::uint64_t>();
    if (keyframes.count(p.reference_id) == 0) {
      r.fail(fmt::format("reference keyframe {} is not in the file", p.reference_id));
    }
    for (int i = 0; i < 3; ++i) p.p_w[i] = r.get<double>();
    if (!p.p_w.allFinite()) r.fail("non-finite position");
    p.visible = r.get<std::int32_t>();
    p.found = r.get<std::int32_t>();
    if (p.visible < 1 || p.found < 1) {
      r.fail(fmt::format("match counters visible {} and found {} (at least 1 each)", p.visible,
                         p.found));
    }
    const std::size_t n = r.count(r.get<std::uint32_t>(), 13, "observations");
    if (n == 0) r.fail("no observation");
    if (n > std::min(kMaxObservations, keyframe_count)) {
      r.fail(fmt::format("{} observations (at most one per keyframe, {} in all)", n,
                         std::min(kMaxObservations, keyframe_count)));
    }
    std::set<KeyFrameId> observers;
    for (std::size_t i = 0; i < n; ++i) {
      const auto kf_id = r.get<std::uint64_t>();
      const auto index = r.get<std::uint32_t>();
      const auto stereo = r.get<std::uint8_t>();
      const auto it = keyframes.find(kf_id);
      if (it == keyframes.end())
        r.fail(fmt::format("observed by keyframe {}, not in the file", kf_id));
      if (index >= it->second->features().size()) {
        r.fail(fmt::format("feature {} of keyframe {}, which has {}", index, kf_id,
                           it->second->features().size()));
      }
      if (stereo > 1) r.fail(fmt::format("stereo flag {}", stereo));
      if (!observers.insert(kf_id).second)
        r.fail(fmt::format("observed twice by keyframe {}", kf_id));
      if (!used_slots.insert({kf_id, index}).second) {
        r.fail(fmt::format("feature {} of keyframe {} holds another point already", index, kf_id));
      }
      p.observations.push_back({kf_id, index, stereo == 1});
    }
    if (observers.count(p.reference_id) == 0) {
      r.fail(fmt::format("its reference keyframe {} does not observe it", p.reference_id));
    }
    next_point_id = std::max(next_point_id, p.id + 1);
    records.push_back(std::move(p));
  }
  if (version >= 2) {
    r.set_record("dense scans");
    constexpr std::size_t kMinScanBytes = 8 + 56 + 4 + 3 * 4;
    const std::size_t scans = r.count(r.get<std::uint64_t>(), kMinScanBytes, "dense scans");
    contents.dense_scans.reserve(scans);
    for (std::size_t k = 0; k < scans; ++k) {
      r.set_record(fmt::format("dense scan {} of {}", k + 1, scans));
      DenseScan scan;
      scan.anchor = r.get<std::uint64_t>();
      if (keyframes.count(scan.anchor) == 0) {
        r.fail(fmt::format("anchored to keyframe {}, not in the file", scan.anchor));
      }
      scan.T_anchor_c = get_pose(r, "pose relative to its anchor");
      const auto step = r.get<std::uint32_t>();
      if (step < 1 || step > static_cast<std::uint32_t>(kMaxPixelStep)) {
        r.fail(fmt::format("pixel step {} (1..{})", step, kMaxPixelStep));
      }
      scan.pixel_step = static_cast<int>(step);
      const cv::Size size = scan_size(info, scan.pixel_step);
      scan.bgr = read_png(r, size, CV_8UC3, "colour image");
      const cv::Mat depth_units = read_png(r, size, CV_16UC1, "depth image");
      scan.exclude = read_png(r, size, CV_8UC1, "exclusion mask");
      if (scan.bgr.empty() || depth_units.empty()) r.fail("no colour or no depth image");
      depth_units.convertTo(scan.depth_m, CV_32FC1, 1.0 / kDepthUnitsPerMetre);
      contents.dense_scans.push_back(std::move(scan));
    }
  }
  r.set_record("");
  // Only zero padding may follow (fewer than 8 bytes).
  const std::size_t rest = payload - r.offset();
  const unsigned char* tail = r.take(rest);
  if (rest >= 8 || std::any_of(tail, tail + rest, [](unsigned char c) { return c != 0; })) {
    r.fail(fmt::format("{} unexpected bytes after the {}", rest,
                       version >= 2 ? "dense scans" : "last map point"));
  }
  for (const auto& [id, parent] : parents) {
    if (id == origin_id ? parent != kNoParent : parent == kNoParent) {
      r.fail(fmt::format("keyframe {}: {}", id,
                         id == origin_id ? "the origin has a parent" : "no parent"));
    }
    if (parent != kNoParent && keyframes.count(static_cast<KeyFrameId>(parent)) == 0) {
      r.fail(fmt::format("keyframe {}: parent {} is not in the file", id, parent));
    }
    // The spanning tree: every parent chain ends at the origin.
    std::set<KeyFrameId> chain{id};
    for (std::int64_t up = parent; up != kNoParent; up = parents[static_cast<KeyFrameId>(up)]) {
      if (!chain.insert(static_cast<KeyFrameId>(up)).second) {
        r.fail(fmt::format("keyframe {}: its parents form a cycle", id));
      }
    }
    for (KeyFrameId other : loop_edges[id]) {
      if (keyframes.count(other) == 0) {
        r.fail(fmt::format("keyframe {}: loop edge to keyframe {}, not in the file", id, other));
      }
    }
  }

  // Build: keyframes (the origin first), their tree and loop edges, the points, then the
  // covisibility graph from the observations.
  map.reserve_ids(next_keyframe_id, next_point_id);
  for (const KeyFramePtr& kf : order) {
    if (!map.add_keyframe(kf)) {
      throw Error(
          fmt::format("{}: the map was reset before and refuses keyframe {}", path, kf->id()));
    }
  }
  for (const KeyFramePtr& kf : order) {
    const std::int64_t parent = parents[kf->id()];
    kf->set_parent(parent == kNoParent ? nullptr : keyframes[static_cast<KeyFrameId>(parent)]);
    for (KeyFrameId other : loop_edges[kf->id()]) kf->add_loop_edge(keyframes[other]);
  }
  for (const PointRecord& rec : records) {
    auto point = std::make_shared<MapPoint>(rec.id, rec.p_w, keyframes[rec.reference_id]);
    for (const PointRecord::Obs& obs : rec.observations) {
      const KeyFramePtr& kf = keyframes[obs.keyframe_id];
      point->add_observation(kf, obs.feature_index, obs.stereo);
      kf->set_map_point(obs.feature_index, point);
    }
    point->increase_visible(rec.visible - 1);
    point->increase_found(rec.found - 1);
    point->compute_distinctive_descriptor();
    point->update_normal_and_depth();
    map.add_map_point(point);
  }
  for (const KeyFramePtr& kf : order) kf->update_connections();
  contents.keyframes = order.size();
  contents.map_points = records.size();
  return contents;
}

}  // namespace ddl::map
