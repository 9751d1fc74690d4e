#include "ddl/map/keyframe.h"

#include <algorithm>

namespace ddl::map {
// Locking rule of the map module: a method never calls into another keyframe or map point while
// holding one of its own locks, so no lock order between entities exists and none can deadlock.

namespace {
constexpr int kCovisibilityThreshold = 15;  // ORB-SLAM2: links need >= 15 shared points
}  // namespace

KeyFrame::KeyFrame(KeyFrameId id, double timestamp_s, std::shared_ptr<const FrameFeatures> features,
                   const SE3& T_c_w)
    : id_(id),
      timestamp_s_(timestamp_s),
      features_(std::move(features)),
      T_c_w_(T_c_w),
      points_(features_->size()) {}

const vocabulary::BowVector& KeyFrame::bow() const {
  if (features_->has_bow()) return features_->bow;
  std::lock_guard lock(bow_mutex_);
  return bow_ ? bow_->bow : features_->bow;
}

const vocabulary::FeatureVector& KeyFrame::feature_vector() const {
  if (features_->has_bow()) return features_->feature_vector;
  std::lock_guard lock(bow_mutex_);
  return bow_ ? bow_->feature_vector : features_->feature_vector;
}

void KeyFrame::set_bow(vocabulary::BowVector bow, vocabulary::FeatureVector feature_vector) {
  if (features_->has_bow()) return;
  std::lock_guard lock(bow_mutex_);
  if (!bow_) bow_ = std::make_unique<const Bow>(Bow{std::move(bow), std::move(feature_vector)});
}

void KeyFrame::compute_bow(const vocabulary::Vocabulary& vocabulary, int levels_up) {
  if (has_bow() || vocabulary.empty()) return;
  vocabulary::BowVector bow;
  vocabulary::FeatureVector feature_vector;
  vocabulary.transform(features_->descriptors, levels_up, bow, feature_vector);
  set_bow(std::move(bow), std::move(feature_vector));
}

SE3 KeyFrame::T_c_w() const {
  std::lock_guard lock(pose_mutex_);
  return T_c_w_;
}

SE3 KeyFrame::T_w_c() const { return T_c_w().inverse(); }

Vec3d KeyFrame::camera_center_w() const { return T_w_c().translation(); }

void KeyFrame::set_T_c_w(const SE3& T_c_w) {
  std::lock_guard lock(pose_mutex_);
  T_c_w_ = T_c_w;
}

MapPointPtr KeyFrame::map_point(std::size_t feature_index) const {
  std::lock_guard lock(points_mutex_);
  return points_[feature_index];
}

std::vector<MapPointPtr> KeyFrame::map_points() const {
  std::lock_guard lock(points_mutex_);
  return points_;
}

std::vector<MapPointPtr> KeyFrame::map_point_set() const {
  std::vector<MapPointPtr> all = map_points();
  std::vector<MapPointPtr> out;
  out.reserve(all.size());
  for (auto& p : all) {
    if (p && !p->is_bad()) out.push_back(std::move(p));
  }
  std::sort(out.begin(), out.end(),
            [](const MapPointPtr& a, const MapPointPtr& b) { return a->id() < b->id(); });
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void KeyFrame::set_map_point(std::size_t feature_index, MapPointPtr point) {
  std::lock_guard lock(points_mutex_);
  points_[feature_index] = std::move(point);
}

void KeyFrame::erase_map_point(std::size_t feature_index) {
  std::lock_guard lock(points_mutex_);
  points_[feature_index].reset();
}

void KeyFrame::erase_map_point(const MapPoint& point) {
  const long index = point.index_in(id_);
  std::lock_guard lock(points_mutex_);
  if (index >= 0 && points_[static_cast<std::size_t>(index)].get() == &point) {
    points_[static_cast<std::size_t>(index)].reset();
    return;
  }
  for (auto& p : points_) {
    if (p.get() == &point) p.reset();
  }
}

int KeyFrame::tracked_map_points(int min_observations) const {
  const std::vector<MapPointPtr> points = map_points();
  int count = 0;
  for (const auto& p : points) {
    if (p && !p->is_bad() && p->num_observations() >= min_observations) ++count;
  }
  return count;
}

void KeyFrame::rebuild_ordered_locked() {
  ordered_.clear();
  for (const auto& [id, link] : links_) ordered_.emplace_back(link.weight, id);
  std::sort(ordered_.begin(), ordered_.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
}

void KeyFrame::update_connections() {
  std::map<KeyFrameId, std::pair<std::shared_ptr<KeyFrame>, int>> counts;
  for (const MapPointPtr& p : map_points()) {
    if (!p || p->is_bad()) continue;
    for (const auto& obs : p->observations()) {
      if (obs.keyframe->id() == id_ || obs.keyframe->is_bad()) continue;
      auto& entry = counts[obs.keyframe->id()];
      entry.first = obs.keyframe;
      ++entry.second;
    }
  }
  if (counts.empty()) return;

  std::shared_ptr<KeyFrame> strongest;
  int strongest_weight = 0;
  std::map<KeyFrameId, Link> links;
  std::map<KeyFrameId, std::weak_ptr<KeyFrame>> connected;
  for (const auto& [id, entry] : counts) {
    connected[id] = entry.first;
    if (entry.second > strongest_weight) {
      strongest_weight = entry.second;
      strongest = entry.first;
    }
    if (entry.second >= kCovisibilityThreshold) links[id] = Link{entry.first, entry.second};
  }
  if (links.empty()) links[strongest->id()] = Link{strongest, strongest_weight};

  const auto self = shared_from_this();
  for (const auto& [id, link] : links) {
    if (auto other = link.keyframe.lock()) other->add_connection(self, link.weight);
  }

  bool needs_parent = false;
  {
    std::lock_guard lock(graph_mutex_);
    links_ = std::move(links);
    connected_ = std::move(connected);
    rebuild_ordered_locked();
    needs_parent = first_connection_ && !origin_.load();
  }
  if (!needs_parent) return;
  // The parent is the strongest covisible (the lowest id among equals, as `strongest` above).
  // One that loop closing is culling on its own thread meanwhile (its observations not yet all
  // erased when they were counted above) refuses the child, and the next strongest is asked
  // (review, stop 25: the child kept a bad parent).
  std::vector<std::pair<int, std::shared_ptr<KeyFrame>>> candidates;  // id order
  for (const auto& [id, entry] : counts) candidates.emplace_back(entry.second, entry.first);
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  // parent_ is written before add_child: once the candidate holds the child, its set_bad() may
  // re-parent it at once, and that must not be overwritten here.
  for (const auto& [weight, candidate] : candidates) {
    {
      std::lock_guard lock(graph_mutex_);
      if (!first_connection_) return;
      parent_ = candidate;
      first_connection_ = false;
    }
    if (candidate->add_child(self)) return;
    std::lock_guard lock(graph_mutex_);  // refused: nobody else has seen this parent
    parent_.reset();
    first_connection_ = true;
  }
}

void KeyFrame::add_connection(const std::shared_ptr<KeyFrame>& other, int weight) {
  std::lock_guard lock(graph_mutex_);
  if (erasing_ || bad_) return;  // being culled: its links are (being) taken apart
  links_[other->id()] = Link{other, weight};
  connected_[other->id()] = other;
  rebuild_ordered_locked();
}

void KeyFrame::erase_connection(KeyFrameId other_id) {
  std::lock_guard lock(graph_mutex_);
  connected_.erase(other_id);
  if (links_.erase(other_id) > 0) rebuild_ordered_locked();
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::connected_keyframes() const {
  std::vector<std::shared_ptr<KeyFrame>> linked;
  {
    std::lock_guard lock(graph_mutex_);
    linked.reserve(connected_.size());
    for (const auto& [id, weak] : connected_) {
      if (auto kf = weak.lock()) linked.push_back(std::move(kf));
    }
  }
  // is_bad() locks the other keyframe: only after releasing our own lock.
  std::vector<std::shared_ptr<KeyFrame>> out;
  for (auto& kf : linked) {
    if (!kf->is_bad()) out.push_back(std::move(kf));
  }
  return out;
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::best_covisibles(std::size_t n) const {
  std::vector<std::shared_ptr<KeyFrame>> linked;
  {
    std::lock_guard lock(graph_mutex_);
    linked.reserve(ordered_.size());
    for (const auto& [weight, id] : ordered_) {
      if (auto kf = links_.at(id).keyframe.lock()) linked.push_back(std::move(kf));
    }
  }
  // is_bad() locks the other keyframe: only after releasing our own lock (locking rule above).
  std::vector<std::shared_ptr<KeyFrame>> out;
  for (auto& kf : linked) {
    if (out.size() >= n) break;
    if (!kf->is_bad()) out.push_back(std::move(kf));
  }
  return out;
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::covisibles() const {
  return best_covisibles(static_cast<std::size_t>(-1));
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::covisibles_with_min_weight(int min_weight) const {
  std::vector<std::shared_ptr<KeyFrame>> linked;
  {
    std::lock_guard lock(graph_mutex_);
    for (const auto& [weight, id] : ordered_) {
      if (weight < min_weight) break;
      if (auto kf = links_.at(id).keyframe.lock()) linked.push_back(std::move(kf));
    }
  }
  std::vector<std::shared_ptr<KeyFrame>> out;
  for (auto& kf : linked) {
    if (!kf->is_bad()) out.push_back(std::move(kf));
  }
  return out;
}

int KeyFrame::weight(KeyFrameId other_id) const {
  std::lock_guard lock(graph_mutex_);
  auto it = links_.find(other_id);
  return it == links_.end() ? 0 : it->second.weight;
}

std::shared_ptr<KeyFrame> KeyFrame::parent() const {
  std::lock_guard lock(graph_mutex_);
  return parent_.lock();
}

void KeyFrame::set_parent(const std::shared_ptr<KeyFrame>& parent) {
  {
    std::lock_guard lock(graph_mutex_);
    parent_ = parent;
    first_connection_ = false;
  }
  if (parent) parent->add_child(shared_from_this());
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::children() const {
  std::lock_guard lock(graph_mutex_);
  std::vector<std::shared_ptr<KeyFrame>> out;
  for (const auto& [id, weak] : children_) {
    if (auto kf = weak.lock()) out.push_back(std::move(kf));
  }
  return out;
}

bool KeyFrame::add_child(const std::shared_ptr<KeyFrame>& child) {
  std::lock_guard lock(graph_mutex_);
  if (erasing_ || bad_) return false;
  children_[child->id()] = child;
  return true;
}

void KeyFrame::erase_child(KeyFrameId child_id) {
  std::lock_guard lock(graph_mutex_);
  children_.erase(child_id);
}

void KeyFrame::add_loop_edge(const std::shared_ptr<KeyFrame>& other) {
  std::lock_guard lock(graph_mutex_);
  not_erase_ = true;
  loop_edges_[other->id()] = other;
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::loop_edges() const {
  std::lock_guard lock(graph_mutex_);
  std::vector<std::shared_ptr<KeyFrame>> out;
  for (const auto& [id, weak] : loop_edges_) {
    if (auto kf = weak.lock()) out.push_back(std::move(kf));
  }
  return out;
}

void KeyFrame::set_not_erase(bool protect) {
  bool erase_now = false;
  {
    std::lock_guard lock(graph_mutex_);
    if (protect) {
      not_erase_ = true;
    } else if (loop_edges_.empty()) {
      not_erase_ = false;
      erase_now = to_be_erased_;
    }
  }
  if (erase_now) set_bad();
}

bool KeyFrame::is_erase_protected() const {
  std::lock_guard lock(graph_mutex_);
  return not_erase_;
}

bool KeyFrame::release_erase_protection() {
  std::lock_guard lock(graph_mutex_);
  if (!loop_edges_.empty()) return false;  // loop edges protect it for good
  not_erase_ = false;
  return to_be_erased_ && !bad_ && !erasing_;
}

bool KeyFrame::is_bad() const {
  std::lock_guard lock(graph_mutex_);
  return bad_;
}

bool KeyFrame::set_bad() {
  std::map<KeyFrameId, Link> links;
  std::map<KeyFrameId, std::weak_ptr<KeyFrame>> connected;
  std::vector<std::shared_ptr<KeyFrame>> children;
  std::shared_ptr<KeyFrame> parent;
  {
    std::lock_guard lock(graph_mutex_);
    if (origin_.load() || bad_ || erasing_) return false;
    if (not_erase_) {
      to_be_erased_ = true;
      return false;
    }
    erasing_ = true;
    links.swap(links_);
    connected.swap(connected_);
    ordered_.clear();
    for (const auto& [id, weak] : children_) {
      if (auto kf = weak.lock()) children.push_back(std::move(kf));
    }
    children_.clear();
    parent = parent_.lock();
  }
  const auto self_id = id_;
  for (const auto& [id, weak] : connected) {  // every link is in `connected` too
    if (auto other = weak.lock()) other->erase_connection(self_id);
  }
  for (const MapPointPtr& p : map_points()) {
    if (p) p->erase_observation(self_id);
  }

  // Re-parent the children: each child takes, among the parent candidates (this keyframe's
  // parent and the children already re-parented), the one it shares most points with.
  std::vector<std::shared_ptr<KeyFrame>> candidates;
  if (parent) candidates.push_back(parent);
  std::vector<std::shared_ptr<KeyFrame>> remaining = children;
  while (!remaining.empty()) {
    int best_weight = -1;
    std::size_t best_child = 0;
    std::shared_ptr<KeyFrame> best_parent;
    for (std::size_t i = 0; i < remaining.size(); ++i) {
      if (remaining[i]->is_bad()) continue;
      for (const auto& c : candidates) {
        const int w = remaining[i]->weight(c->id());
        if (w > best_weight) {
          best_weight = w;
          best_child = i;
          best_parent = c;
        }
      }
    }
    if (!best_parent || best_weight <= 0) break;
    remaining[best_child]->set_parent(best_parent);
    candidates.push_back(remaining[best_child]);
    remaining.erase(remaining.begin() + static_cast<long>(best_child));
  }
  for (const auto& child : remaining) {
    if (parent) child->set_parent(parent);
  }
  if (parent) parent->erase_child(self_id);

  const SE3 T_w_parent = parent ? parent->T_w_c() : SE3();
  {
    std::lock_guard lock(pose_mutex_);
    T_c_parent_ = T_c_w_ * T_w_parent;
  }
  std::lock_guard lock(graph_mutex_);
  bad_ = true;
  return true;
}

SE3 KeyFrame::T_c_parent_at_removal() const {
  std::lock_guard lock(pose_mutex_);
  return T_c_parent_;
}

}  // namespace ddl::map
