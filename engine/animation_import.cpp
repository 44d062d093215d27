#include "engine/animation_import.h"

#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <cstring>
#include <numbers>

#include "engine/isolated.h"

namespace ponyhop {

namespace {

std::optional<ImportedAnimation> fail(std::string* error, const std::string& msg) {
  if (error) *error = msg;
  return std::nullopt;
}

Eigen::Vector3d toEigen(const aiVector3D& v) { return {v.x, v.y, v.z}; }
Eigen::Quaterniond toEigen(const aiQuaternion& q) { return Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized(); }

// Index i of the last key with time <= t (-1 when t is before the first key).
template <class Key>
int keyBefore(const Key* keys, int n, double t) {
  const Key* it = std::upper_bound(keys, keys + n, t, [](double tt, const Key& k) { return tt < k.mTime; });
  return static_cast<int>(it - keys) - 1;
}

// Piecewise-linear position at tick t, holding the end keys.
Eigen::Vector3d positionAt(const aiNodeAnim& ch, double t) {
  const int n = static_cast<int>(ch.mNumPositionKeys);
  const int i = keyBefore(ch.mPositionKeys, n, t);
  if (i < 0) return toEigen(ch.mPositionKeys[0].mValue);
  if (i >= n - 1) return toEigen(ch.mPositionKeys[n - 1].mValue);
  const aiVectorKey &a = ch.mPositionKeys[i], &b = ch.mPositionKeys[i + 1];
  const double u = (t - a.mTime) / (b.mTime - a.mTime);
  return (1.0 - u) * toEigen(a.mValue) + u * toEigen(b.mValue);
}

// Slerp (shortest arc) rotation at tick t, holding the end keys.
Eigen::Quaterniond rotationAt(const aiNodeAnim& ch, double t) {
  const int n = static_cast<int>(ch.mNumRotationKeys);
  const int i = keyBefore(ch.mRotationKeys, n, t);
  if (i < 0) return toEigen(ch.mRotationKeys[0].mValue);
  if (i >= n - 1) return toEigen(ch.mRotationKeys[n - 1].mValue);
  const aiQuatKey &a = ch.mRotationKeys[i], &b = ch.mRotationKeys[i + 1];
  const double u = (t - a.mTime) / (b.mTime - a.mTime);
  return toEigen(a.mValue).slerp(u, toEigen(b.mValue)).normalized();
}

std::optional<ImportedAnimation> importHere(const std::string& path, const AnimationImportOptions& opt,
                                            std::string* error);

// ImportedAnimation through the pipe from the import process.
void putBytes(std::string& s, const void* p, size_t n) { s.append(static_cast<const char*>(p), n); }
void putString(std::string& s, const std::string& v) {
  const uint64_t n = v.size();
  putBytes(s, &n, sizeof(n));
  s += v;
}
struct Reader {
  const std::string& s;
  size_t at = 0;
  bool ok = true;
  void get(void* p, size_t n) {
    if (!ok || s.size() - at < n) {
      ok = false;
      return;
    }
    std::memcpy(p, s.data() + at, n);
    at += n;
  }
  std::string string() {
    uint64_t n = 0;
    get(&n, sizeof(n));
    if (!ok || n > s.size() - at) {
      ok = false;
      return {};
    }
    std::string v = s.substr(at, size_t(n));
    at += size_t(n);
    return v;
  }
};

std::string serialize(const ImportedAnimation& a) {
  std::string s;
  putString(s, a.animation_name);
  putString(s, a.node_name);
  putBytes(s, &a.ticks_per_second, sizeof(double));
  putBytes(s, &a.position_keys, sizeof(int));
  putBytes(s, &a.rotation_keys, sizeof(int));
  const uint64_t n = a.samples.size();
  putBytes(s, &n, sizeof(n));
  for (const PoseSample& p : a.samples) {
    const double v[8] = {
        p.t,           p.position.x(), p.position.y(), p.position.z(), p.rotation.w(), p.rotation.x(), p.rotation.y(),
        p.rotation.z()};
    putBytes(s, v, sizeof(v));
  }
  return s;
}

bool deserialize(const std::string& s, ImportedAnimation& a) {
  Reader r{s};
  a.animation_name = r.string();
  a.node_name = r.string();
  r.get(&a.ticks_per_second, sizeof(double));
  r.get(&a.position_keys, sizeof(int));
  r.get(&a.rotation_keys, sizeof(int));
  uint64_t n = 0;
  r.get(&n, sizeof(n));
  if (!r.ok || n > (s.size() - r.at) / (8 * sizeof(double))) return false;
  a.samples.resize(size_t(n));
  for (PoseSample& p : a.samples) {
    double v[8];
    r.get(v, sizeof(v));
    p.t = v[0];
    p.position = Eigen::Vector3d(v[1], v[2], v[3]);
    p.rotation = Eigen::Quaterniond(v[4], v[5], v[6], v[7]);
  }
  return r.ok && r.at == s.size();
}

}  // namespace

std::optional<ImportedAnimation> importAnimation(const std::string& path, const AnimationImportOptions& opt,
                                                 std::string* error) {
  // assimp runs in a child process with a time and memory limit (engine/isolated.h), as for
  // meshes: a file that crashes or hangs it costs a message, not ponyhop.
  std::string bytes, e;
  const bool ok = runIsolated(
      [&](std::string& result, std::string& err) {
        const std::optional<ImportedAnimation> a = importHere(path, opt, &err);
        if (!a) return false;
        result = serialize(*a);
        return true;
      },
      importLimits(), &bytes, &e);
  if (!ok) return fail(error, e.rfind(path, 0) == 0 ? e : path + ": the importer (assimp) " + e);
  ImportedAnimation a;
  if (!deserialize(bytes, a)) return fail(error, path + ": the import process returned inconsistent data");
  return a;
}

namespace {

std::optional<ImportedAnimation> importHere(const std::string& path, const AnimationImportOptions& opt,
                                            std::string* error) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, 0);
  if (!scene) return fail(error, path + ": cannot read the animation: " + importer.GetErrorString());
  if (scene->mNumAnimations == 0 || !scene->mAnimations)
    return fail(error, path + ": has no animation (export one with the mesh, or use a clip from assets/animations/)");

  const aiAnimation* anim = nullptr;
  if (opt.animation.empty()) {
    anim = scene->mAnimations[0];
  } else {
    std::string names;
    for (unsigned i = 0; i < scene->mNumAnimations; ++i) {
      const std::string name = scene->mAnimations[i]->mName.C_Str();
      if (name == opt.animation) anim = scene->mAnimations[i];
      names += (i ? ", \"" : "\"") + name + "\"";
    }
    if (!anim) return fail(error, path + ": no animation named \"" + opt.animation + "\" (it has " + names + ")");
  }
  if (anim->mNumChannels == 0)
    return fail(error, path + ": animation \"" + std::string(anim->mName.C_Str()) + "\" animates no node");

  const aiNodeAnim* ch = nullptr;
  if (opt.node.empty()) {
    ch = anim->mChannels[0];
  } else {
    std::string names;
    for (unsigned i = 0; i < anim->mNumChannels; ++i) {
      const std::string name = anim->mChannels[i]->mNodeName.C_Str();
      if (name == opt.node) ch = anim->mChannels[i];
      names += (i ? ", \"" : "\"") + name + "\"";
    }
    if (!ch)
      return fail(error, path + ": animation \"" + std::string(anim->mName.C_Str()) + "\" does not animate node \"" +
                             opt.node + "\" (it animates " + names + ")");
  }
  if (ch->mNumPositionKeys == 0 && ch->mNumRotationKeys == 0)
    return fail(error, path + ": node \"" + std::string(ch->mNodeName.C_Str()) + "\" has no position or rotation keys");

  ImportedAnimation out;
  out.animation_name = anim->mName.C_Str();
  out.node_name = ch->mNodeName.C_Str();
  out.ticks_per_second = anim->mTicksPerSecond > 0 ? anim->mTicksPerSecond : 25.0;  // assimp's documented default
  out.position_keys = static_cast<int>(ch->mNumPositionKeys);
  out.rotation_keys = static_cast<int>(ch->mNumRotationKeys);

  // The node's rest pose supplies a channel that has no keys; its parents' (static) transform
  // places the node's local motion in the file's frame.
  const aiNode* node = scene->mRootNode ? scene->mRootNode->FindNode(ch->mNodeName) : nullptr;
  aiVector3D restScale, restPos;
  aiQuaternion restRot;
  if (node) node->mTransformation.Decompose(restScale, restRot, restPos);
  aiMatrix4x4 parent;  // identity
  for (const aiNode* p = node ? node->mParent : nullptr; p; p = p->mParent) parent = p->mTransformation * parent;
  aiVector3D parentScale, parentPos;
  aiQuaternion parentRot;
  parent.Decompose(parentScale, parentRot, parentPos);
  const Eigen::Quaterniond Rp = toEigen(parentRot);
  const Eigen::Vector3d Sp = toEigen(parentScale), Tp = toEigen(parentPos);

  // Union of the key times (ticks), merged within a millionth of a tick.
  std::vector<double> ticks;
  for (unsigned i = 0; i < ch->mNumPositionKeys; ++i) ticks.push_back(ch->mPositionKeys[i].mTime);
  for (unsigned i = 0; i < ch->mNumRotationKeys; ++i) ticks.push_back(ch->mRotationKeys[i].mTime);
  std::sort(ticks.begin(), ticks.end());
  ticks.erase(std::unique(ticks.begin(), ticks.end(), [](double a, double b) { return std::abs(a - b) < 1e-6; }),
              ticks.end());

  const Eigen::Quaterniond C(Eigen::AngleAxisd(0.5 * std::numbers::pi, Eigen::Vector3d::UnitX()));  // y up -> z up
  Eigen::Quaterniond prev = Eigen::Quaterniond::Identity();
  for (double tick : ticks) {
    PoseSample s;
    s.t = tick / out.ticks_per_second;
    const Eigen::Vector3d p = ch->mNumPositionKeys ? positionAt(*ch, tick) : toEigen(restPos);
    const Eigen::Quaterniond q = ch->mNumRotationKeys ? rotationAt(*ch, tick) : toEigen(restRot);
    s.position = Rp * Sp.cwiseProduct(p) + Tp;
    s.rotation = Rp * q;
    if (opt.y_up_to_z_up) {
      s.position = C * s.position;
      s.rotation = C * s.rotation * C.conjugate();
    }
    // Keep consecutive quaternions in one hemisphere (same rotations; easier to read and compare).
    if (s.rotation.coeffs().dot(prev.coeffs()) < 0) s.rotation.coeffs() *= -1.0;
    prev = s.rotation;
    out.samples.push_back(s);
  }
  return out;
}

}  // namespace

std::optional<KeyframeTrack> importAnimationTrack(const std::string& path, const AnimationImportOptions& options,
                                                  const TrackOptions& track, std::string* error) {
  const std::optional<ImportedAnimation> anim = importAnimation(path, options, error);
  if (!anim) return std::nullopt;
  KeyframeTrack tr;
  if (Status s = KeyframeTrack::fromSamples(anim->samples, track, tr); !s.ok()) {
    if (error) *error = path + ": animation \"" + anim->animation_name + "\": " + s.message();
    return std::nullopt;
  }
  return tr;
}

}  // namespace ponyhop
