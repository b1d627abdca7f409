#include "sim/state_io.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <type_traits>

#include "sim/simulation.h"

namespace fp::sim {

namespace {

constexpr char kMagic[8] = {'F', 'P', 'S', 'T', 'A', 'T', 'E', '\0'};
constexpr std::uint64_t kFnvOffset = 1469598103934665603ull;
constexpr std::uint64_t kFnvPrime = 1099511628211ull;

std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t h = kFnvOffset) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    h ^= p[i];
    h *= kFnvPrime;
  }
  return h;
}

/// element types stored as raw bytes: plain scalars and Eigen's fixed vectors (contiguous coefficients)
template <class T>
constexpr bool kRawBytes =
    std::is_trivially_copyable_v<T> || std::is_same_v<T, Vec3> || std::is_same_v<T, Vec3d>;
static_assert(sizeof(Vec3) == 3 * sizeof(Real) && sizeof(Vec3d) == 3 * sizeof(double));

bool littleEndian() {
  const std::uint32_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

/// Appends plain values in the host's (little-endian) byte order.
class Writer {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const char*>(&value);
    m_bytes.append(p, sizeof(T));
  }
  void putVec(const Vec3d& v) {
    for (int k = 0; k < 3; ++k)
      put(v[k]);
  }
  template <class T>
  void putArray(const std::vector<T>& values) {
    static_assert(kRawBytes<T>);
    put(std::uint64_t(values.size()));
    m_bytes.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
  }
  // the field lists' interface (shared with Reader): one call per field, with its name for errors
  template <class T>
  void field(const T& value, const char*) {
    if constexpr (std::is_same_v<T, Vec3d>)
      putVec(value);
    else
      put(value);
  }
  template <class T>
  void array(const std::vector<T>& values, const char*) {
    putArray(values);
  }
  std::string& bytes() { return m_bytes; }

 private:
  std::string m_bytes;
};

/// Reads what Writer wrote; every read checks the bytes left, every count against them.
class Reader {
 public:
  explicit Reader(std::string_view bytes) : m_bytes(bytes) {}
  template <class T>
  T get(const char* what) {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, m_bytes.data() + m_pos, sizeof(T));
    m_pos += sizeof(T);
    return value;
  }
  Vec3d getVec(const char* what) {
    Vec3d v;
    for (int k = 0; k < 3; ++k)
      v[k] = get<double>(what);
    return v;
  }
  template <class T>
  std::vector<T> getArray(const char* what) {
    const std::uint64_t count = get<std::uint64_t>(what);
    if (count > (m_bytes.size() - m_pos) / sizeof(T))
      throw StateError(std::string("truncated or corrupt: ") + what + " claims " + std::to_string(count) +
                       " entries, more than the file holds");
    static_assert(kRawBytes<T>);
    std::vector<T> values{};
    values.resize(std::size_t(count));
    if (count >
        0)  // an empty vector's data() may be null, and memcpy's pointers must not be even for 0 bytes
      std::memcpy(static_cast<void*>(values.data()), m_bytes.data() + m_pos, std::size_t(count) * sizeof(T));
    m_pos += std::size_t(count) * sizeof(T);
    return values;
  }
  template <class T>
  void field(T& value, const char* what) {
    if constexpr (std::is_same_v<T, Vec3d>)
      value = getVec(what);
    else
      value = get<T>(what);
  }
  template <class T>
  void array(std::vector<T>& values, const char* what) {
    values = getArray<T>(what);
  }
  std::size_t pos() const { return m_pos; }
  std::size_t size() const { return m_bytes.size(); }

 private:
  void need(std::size_t n, const char* what) const {
    if (m_bytes.size() - m_pos < n) {
      throw StateError(std::string("truncated: the file ends at byte ") + std::to_string(m_bytes.size()) +
                       " in " + what);
    }
  }
  std::string_view m_bytes;
  std::size_t m_pos = 0;
};

/// Scene description as a stream of hashed numbers.
class Hasher {
 public:
  template <class T>
  void add(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    m_h = fnv1a(&value, sizeof(T), m_h);
  }
  void add(const Vec3d& v) {
    for (int k = 0; k < 3; ++k)
      add(v[k]);
  }
  void add(const Quatd& q) {
    add(q.w());
    add(q.x());
    add(q.y());
    add(q.z());
  }
  void add(const std::string& s) {
    add(std::uint64_t(s.size()));
    m_h = fnv1a(s.data(), s.size(), m_h);
  }
  std::uint64_t value() const { return m_h; }

 private:
  std::uint64_t m_h = kFnvOffset;
};

/// every parameter of the table as doubles, Vector3 ones as three
std::vector<double> paramValues(const SimParams& p) {
  std::vector<double> out;
  for (const ParamInfo& info : ParamTable::sim().entries()) {
    if (info.kind == ParamKind::Vector3) {
      for (double c : ParamTable::getVec3(p, info))
        out.push_back(c);
    } else {
      out.push_back(ParamTable::getScalar(p, info));
    }
  }
  return out;
}

template <class V>
bool allFinite(const std::vector<V>& values) {
  for (const V& v : values) {
    if constexpr (std::is_floating_point_v<V>) {
      if (!std::isfinite(v))
        return false;
    } else {
      if (!v.allFinite())
        return false;
    }
  }
  return true;
}

bool isNaN(const std::vector<Real>& values) {
  for (Real v : values) {
    if (std::isnan(v))
      return true;
  }
  return false;
}

// The field lists: each names the fields of a record once, in file order, for the writer and the reader alike
// (Io is Writer or Reader, R the record, const when written).

template <class Io, class R>
void adaptivityFields(Io& io, R& a) {
  const char* what = "run statistics";
  io.field(a.splits, what);
  io.field(a.children, what);
  io.field(a.merges, what);
  io.field(a.redistributions, what);
  io.field(a.splitsBlocked, what);
  io.field(a.splitsCompared, what);
  io.field(a.splitErrorChosen, what);
  io.field(a.splitErrorUnrotated, what);
}

static_assert(sizeof(std::size_t) == 8 && sizeof(int) == 4, "the format stores size_t in 8 bytes, int in 4");

template <class Io, class R>
void runFields(Io& io, R& run) {
  const char* what = "run statistics";
  io.field(run.steps, what);
  io.field(run.particleSteps, what);
  io.field(run.particlesMax, what);
  io.field(run.simTime, what);
  io.field(run.densityErrorSum, what);
  io.field(run.densityErrorMax, what);
  io.field(run.densityIterations, what);
  io.field(run.divergenceIterations, what);
  io.field(run.neighborsSum, what);
  adaptivityFields(io, run.adaptivity);
  io.field(run.heldParticleSteps, what);
  io.field(run.level1ParticleSteps, what);
  io.field(run.maxSpeed, what);
  io.field(run.maxSpeedTime, what);
  io.field(run.cagedParticleSteps, what);
}

template <class Io, class R>
void lastStepFields(Io& io, R& last) {
  const char* what = "last step";
  io.field(last.dt, what);
  io.field(last.densityIterations, what);
  io.field(last.divergenceIterations, what);
  io.field(last.densityError, what);
  io.field(last.solverDensityError, what);
  io.field(last.fluidNeighbors, what);
  io.field(last.boundaryNeighbors, what);
  adaptivityFields(io, last.adaptivity);
  io.field(last.heldParticles, what);
  io.field(last.maxSpeed, what);
  io.field(last.cagedParticles, what);
}

}  // namespace

/// The private state of a Simulation that a saved state holds (friend of Simulation and ParticleSet).
class StateAccess {
 public:
  struct Pose {
    Vec3d position, linearVelocity, angularVelocity;
    Quatd orientation;
  };
  struct State {
    std::uint32_t mode = 0;
    double time = 0;
    Real dt = 0;
    std::uint64_t stepCount = 0;
    Vec3d boundaryImpulse = Vec3d::Zero();
    SimParams params;
    std::vector<Pose> colliders;
    std::uint32_t nextId = 0;
    ParticleSet fluid;
    BoundarySet boundary;  // the per-particle arrays only
    RunStats run;
    StepStats last;
    std::uint64_t level1 = 0;  // particles on time level 1 at the last synchronised step (time_levels = 2)
    std::vector<double> extra;
  };

  /// every per-particle array of the fluid, in file order: f(member, name, adaptivity field: empty in the
  /// uniform modes)
  template <class F>
  static void particleArrays(F&& f) {
    f(&ParticleSet::x, "positions", false);
    f(&ParticleSet::v, "velocities", false);
    f(&ParticleSet::a, "accelerations", false);
    f(&ParticleSet::m, "masses", false);
    f(&ParticleSet::H, "support radii", false);
    f(&ParticleSet::rho, "densities", false);
    f(&ParticleSet::kappa, "density stiffness", false);
    f(&ParticleSet::kappaV, "divergence stiffness", false);
    f(&ParticleSet::splitTime, "split times", true);
    f(&ParticleSet::id, "ids", false);
    f(&ParticleSet::flags, "flags", false);
    f(&ParticleSet::levelPhi, "visible levels", true);
    f(&ParticleSet::levelOmega, "vorticity levels", true);
    f(&ParticleSet::levelNu, "velocity-difference levels", true);
    f(&ParticleSet::mOpt, "optimal masses", true);
    f(&ParticleSet::phi, "surface distances", true);
    f(&ParticleSet::omega, "vorticities", true);
    f(&ParticleSet::nu, "velocity differences", true);
    f(&ParticleSet::heavySteps, "split delays", true);
    f(&ParticleSet::parentId, "split parent ids", true);
    f(&ParticleSet::splitAge, "split ages", true);
  }
  /// every per-particle array of the boundary, in file order: f(member, name, kinematic particles only)
  template <class F>
  static void boundaryArrays(F&& f) {
    f(&BoundarySet::x, "boundary positions", false);
    f(&BoundarySet::v, "boundary velocities", true);
    f(&BoundarySet::psi, "boundary volumes", false);
    f(&BoundarySet::local, "boundary local positions", true);
    f(&BoundarySet::collider, "boundary colliders", false);
  }
  /// a collider's pose (Pose or ColliderState): position, orientation (w, x, y, z), velocities
  template <class Io, class P>
  static void poseFields(Io& io, P& p) {
    const char* what = "a collider pose";
    io.field(p.position, what);
    double q[4] = {p.orientation.w(), p.orientation.x(), p.orientation.y(), p.orientation.z()};
    for (double& c : q)
      io.field(c, what);
    if constexpr (!std::is_const_v<P>)
      p.orientation = Quatd(q[0], q[1], q[2], q[3]);
    io.field(p.linearVelocity, what);
    io.field(p.angularVelocity, what);
  }

  static std::string encode(const Simulation& sim, const std::vector<double>& extra) {
    Writer w;
    w.bytes().append(kMagic, sizeof(kMagic));
    w.put(kStateVersion);
    w.put(sceneHash(sim.m_scene));
    w.put(std::uint32_t(sim.m_mode));
    w.put(sim.m_time);
    w.put(sim.m_dt);
    w.put(sim.m_stepCount);
    w.putVec(sim.m_boundaryImpulse);
    w.putArray(paramValues(sim.m_params));
    w.put(std::uint64_t(sim.m_colliders.size()));
    for (const ColliderState& c : sim.m_colliders)
      poseFields(w, c);
    w.put(sim.m_fluid.m_nextId);
    particleArrays([&](auto member, const char* what, bool) { w.array(sim.m_fluid.*member, what); });
    boundaryArrays([&](auto member, const char* what, bool) { w.array(sim.m_boundary.*member, what); });
    runFields(w, sim.m_run);
    lastStepFields(w, sim.m_last);
    w.put(std::uint64_t(sim.m_level1));
    w.putArray(extra);
    const std::uint64_t sum = fnv1a(w.bytes().data(), w.bytes().size());
    w.put(sum);
    return std::move(w.bytes());
  }

  static State parse(std::string_view bytes, const Simulation& sim, bool verifyChecksum) {
    if (!littleEndian())
      throw StateError("saved states are little-endian; this machine is not");
    if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
      throw StateError("not a FluidPlaying state file (bad magic)");
    Reader r(bytes.substr(sizeof(kMagic)));
    const auto version = r.get<std::uint32_t>("the version");
    if (version != kStateVersion) {
      throw StateError("state file version " + std::to_string(version) + ", this build reads version " +
                       std::to_string(kStateVersion));
    }
    const auto hash = r.get<std::uint64_t>("the scene hash");
    if (verifyChecksum) {
      // checked before anything else is believed: a flipped byte anywhere is reported as corruption
      if (bytes.size() < sizeof(kMagic) + 20 + sizeof(std::uint64_t))
        throw StateError("truncated: the file ends at byte " + std::to_string(bytes.size()));
      const std::size_t body = bytes.size() - sizeof(std::uint64_t);
      std::uint64_t stored = 0;
      std::memcpy(&stored, bytes.data() + body, sizeof(stored));
      if (fnv1a(bytes.data(), body) != stored)
        throw StateError("corrupt or truncated: checksum mismatch");
    }
    if (hash != sceneHash(sim.m_scene)) {
      throw StateError(
          "saved from another scene or scene settings (scene hash differs; same scene file, "
          "--mode, --seed and hand size needed)");
    }
    State s;
    s.mode = r.get<std::uint32_t>("the mode");
    if (s.mode != std::uint32_t(sim.m_mode))
      throw StateError("saved in another resolution mode");
    s.time = r.get<double>("the time");
    s.dt = r.get<Real>("the step size");
    s.stepCount = r.get<std::uint64_t>("the step counter");
    s.boundaryImpulse = r.getVec("the boundary impulse");
    if (!std::isfinite(s.time) || s.time < 0 || !std::isfinite(s.dt) || !(s.dt > 0) ||
        !s.boundaryImpulse.allFinite()) {
      throw StateError("corrupt: bad time, step size or impulse");
    }

    const std::vector<double> values = r.getArray<double>("the parameters");
    if (values.size() != paramValues(sim.m_params).size())
      throw StateError("corrupt: " + std::to_string(values.size()) + " parameter values");
    // live parameters may have been edited during the run; the others are the scene's (hashed above)
    s.params = sim.m_params;
    std::size_t k = 0;
    for (const ParamInfo& info : ParamTable::sim().entries()) {
      const std::size_t width = info.kind == ParamKind::Vector3 ? 3 : 1;
      std::vector<double> current;
      if (info.kind == ParamKind::Vector3) {
        for (double c : ParamTable::getVec3(sim.m_params, info))
          current.push_back(c);
      } else {
        current.push_back(ParamTable::getScalar(sim.m_params, info));
      }
      const std::vector<double> saved(values.begin() + std::ptrdiff_t(k),
                                      values.begin() + std::ptrdiff_t(k + width));
      k += width;
      if (!info.live) {
        if (saved != current)
          throw StateError("parameter " + info.key + " differs from the scene's, and it is not live");
        continue;
      }
      const std::string error = info.kind == ParamKind::Vector3
                                    ? ParamTable::setVec3(s.params, info, {saved[0], saved[1], saved[2]})
                                    : ParamTable::setScalar(s.params, info, saved[0]);
      if (!error.empty())
        throw StateError("corrupt parameter: " + error);
    }
    const std::string invalid = ParamTable::validate(s.params);
    if (!invalid.empty())
      throw StateError("corrupt parameters: " + invalid);

    const auto colliders = r.get<std::uint64_t>("the colliders");
    if (colliders != sim.m_colliders.size())
      throw StateError("saved with " + std::to_string(colliders) + " colliders, the scene has " +
                       std::to_string(sim.m_colliders.size()));
    for (std::size_t c = 0; c < sim.m_colliders.size(); ++c) {
      Pose p;
      poseFields(r, p);
      if (!p.position.allFinite() || !p.orientation.coeffs().allFinite() || !p.linearVelocity.allFinite() ||
          !p.angularVelocity.allFinite() || std::abs(p.orientation.norm() - 1.0) > 1e-6) {
        throw StateError("corrupt: collider " + std::to_string(c) + " has a bad pose");
      }
      s.colliders.push_back(p);
    }

    ParticleSet& f = s.fluid;
    const bool adaptivityFields = sim.m_fluid.hasAdaptivityFields();
    f.setAdaptivityFields(adaptivityFields);
    s.nextId = r.get<std::uint32_t>("the particle ids");
    particleArrays([&](auto member, const char* what, bool) { r.array(f.*member, what); });
    const std::size_t n = f.x.size();
    particleArrays([&](auto member, const char*, bool adaptivity) {
      if ((f.*member).size() != (adaptivity && !adaptivityFields ? 0 : n))
        throw StateError("corrupt: particle fields of different lengths");
    });
    if (n == 0)
      throw StateError("corrupt: no fluid particle");
    const Vec3 lo = sim.m_scene.domain.min().cast<Real>();
    const Vec3 hi = sim.m_scene.domain.max().cast<Real>();
    // The largest particle any mass ratio the table allows can make, with a factor of 8 in mass (2 in size)
    // to spare: a finite but absurd mass or support (1e38) would overflow the grid's cell counts.
    const double ratioMax = ParamTable::sim().at("mass_ratio").max;
    const double mMax = 8.0 * ratioMax * double(sim.m_latticeMass);
    const double hMax = 2.0 * std::cbrt(ratioMax) * double(sim.m_support);
    for (std::size_t i = 0; i < n; ++i) {
      if (!((f.x[i].array() >= lo.array()).all() && (f.x[i].array() <= hi.array()).all()))
        throw StateError("corrupt: particle " + std::to_string(i) + " lies outside the domain");
      if (!(f.m[i] > 0) || !(f.H[i] > 0) || !(double(f.m[i]) <= mMax) || !(double(f.H[i]) <= hMax) ||
          f.id[i] >= s.nextId)
        throw StateError("corrupt: particle " + std::to_string(i) + " has a bad mass, support or id");
    }
    if (!allFinite(f.v) || !allFinite(f.a) || !allFinite(f.rho) || !allFinite(f.kappa) ||
        !allFinite(f.kappaV) || !allFinite(f.mOpt) || isNaN(f.splitTime) || isNaN(f.levelPhi) ||
        isNaN(f.levelOmega) || isNaN(f.levelNu) || isNaN(f.phi) || isNaN(f.omega) || isNaN(f.nu)) {
      throw StateError("corrupt: a particle field is not finite");
    }

    BoundarySet& b = s.boundary;
    boundaryArrays([&](auto member, const char* what, bool) { r.array(b.*member, what); });
    const std::size_t nb = sim.m_boundary.size();
    const std::size_t nStatic = sim.m_boundary.staticCount();
    boundaryArrays([&](auto member, const char*, bool kinematic) {
      if ((b.*member).size() != (kinematic ? nb - nStatic : nb))
        throw StateError("saved with another number of boundary particles than the scene has");
    });
    for (std::uint16_t c : b.collider) {
      if (c >= sim.m_colliders.size())
        throw StateError("corrupt: a boundary particle names collider " + std::to_string(c));
    }
    // the static particles never move nor reorder: they must be the scene's own
    for (std::size_t i = 0; i < sim.m_boundary.staticCount(); ++i) {
      if (b.collider[i] != sim.m_boundary.collider[i] || b.x[i] != sim.m_boundary.x[i])
        throw StateError("saved with other static boundaries than the scene has");
    }
    if (!allFinite(b.x) || !allFinite(b.v) || !allFinite(b.psi) || !allFinite(b.local)) {
      throw StateError("corrupt: a boundary field is not finite");
    }

    runFields(r, s.run);
    lastStepFields(r, s.last);
    // the figures the reports print (a NaN would stay the run's largest speed for good), and the last step's
    // size, by which the app paces its steps (resetRunStats() keeps the last step: with no step in the run
    // since, its speed may exceed the run's)
    auto figure = [](double x) { return std::isfinite(x) && x >= 0.0; };
    const RunStats& run = s.run;
    if (!figure(run.simTime) || !figure(run.densityErrorSum) || !figure(run.densityErrorMax) ||
        !figure(run.neighborsSum) || !figure(run.maxSpeed) || !figure(run.maxSpeedTime) ||
        run.maxSpeedTime > s.time) {
      throw StateError("corrupt: bad run statistics");
    }
    constexpr double kLongestStep = 1.0;  // [s] (dt_max is at most 0.05 s)
    const StepStats& last = s.last;
    if (!figure(last.dt) || last.dt > kLongestStep || !figure(last.densityError) ||
        !std::isfinite(last.solverDensityError) || !figure(last.fluidNeighbors) ||
        !figure(last.boundaryNeighbors) || !figure(last.maxSpeed) ||
        (run.steps > 0 && last.maxSpeed > run.maxSpeed)) {
      throw StateError("corrupt: bad figures of the last step");
    }
    s.level1 = r.get<std::uint64_t>("the time levels");  // (a counter, like the run's)
    s.extra = r.getArray<double>("the app state");
    r.get<std::uint64_t>("the checksum");
    if (r.pos() != r.size())
      throw StateError("corrupt: " + std::to_string(r.size() - r.pos()) + " bytes after the end");
    return s;
  }

  static void apply(State&& s, Simulation& sim) {
    sim.m_time = s.time;
    sim.m_dt = s.dt;
    sim.m_stepCount = s.stepCount;
    sim.m_boundaryImpulse = s.boundaryImpulse;
    sim.m_params = s.params;
    for (std::size_t c = 0; c < s.colliders.size(); ++c) {
      ColliderState& target = sim.m_colliders[c];
      target.position = s.colliders[c].position;
      target.orientation = s.colliders[c].orientation;
      target.linearVelocity = s.colliders[c].linearVelocity;
      target.angularVelocity = s.colliders[c].angularVelocity;
    }
    sim.m_fluid = std::move(s.fluid);
    sim.m_fluid.m_nextId = s.nextId;
    // a loaded support is not trusted to be its mass's own: the next blend checks every particle again (and,
    // where it is, gives the same support, so a restored run stays bit-identical)
    for (std::uint32_t& f : sim.m_fluid.flags)
      f &= ~std::uint32_t(kFlagSupportSettled);
    boundaryArrays(
        [&](auto member, const char*, bool) { sim.m_boundary.*member = std::move(s.boundary.*member); });
    sim.m_run = s.run;
    sim.m_last = s.last;
    // time levels (time_levels = 2): the next synchronised step gives the particles held in the last step
    // their gravity, and a step between two synchronised ones counts the last one's level-1 particles
    sim.m_heldLastStep = s.last.heldParticles > 0;
    sim.m_level1 = std::size_t(s.level1);
    // Neighbour lists valid for the restored particles, as after a step (readers such as the splash use
    // them). The sort is stable and the positions are those of the last sort, so the order does not change.
    sim.m_fluidPresorted = false;  // (the grid's cells are those of the particles replaced)
    sim.searchNeighbors();
    sim.m_neighborsCurrent = false;  // the next step searches them again, as after a step
    sim.m_preparedSeconds = 0.0;
  }
};

std::uint64_t sceneHash(const SceneDesc& scene) {
  Hasher h;
  h.add(scene.domain.min());
  h.add(scene.domain.max());
  for (double v : paramValues(scene.params))
    h.add(v);
  h.add(std::uint64_t(scene.fluid.size()));
  for (const FluidBlock& b : scene.fluid) {
    h.add(b.box.min());
    h.add(b.box.max());
    h.add(b.velocity);
  }
  h.add(std::uint64_t(scene.colliders.size()));
  for (const ColliderDesc& c : scene.colliders) {
    h.add(c.name);
    h.add(std::uint32_t(c.shape));
    h.add(c.halfExtents);
    h.add(c.radius);
    h.add(c.halfLength);
    h.add(std::uint8_t(c.container));
    if (c.headroom != 0.0)  // (only when set: the hashes of the scenes without it stay as they were)
      h.add(c.headroom);
    h.add(c.position);
    h.add(c.orientation);
    h.add(c.linearVelocity);
    h.add(c.angularVelocity);
    h.add(std::uint8_t(c.driven));
    if (c.mesh) {
      h.add(std::uint64_t(c.mesh->vertices.size()));
      for (const Vec3d& v : c.mesh->vertices)
        h.add(v);
      h.add(std::uint64_t(c.mesh->triangles.size()));
      for (const auto& t : c.mesh->triangles)
        h.add(t);
    }
  }
  h.add(scene.frameRate);
  h.add(std::uint32_t(scene.mode));
  return h.value();
}

std::string encodeState(const Simulation& sim, const std::vector<double>& extra) {
  return StateAccess::encode(sim, extra);
}

std::vector<double> decodeState(std::string_view bytes, Simulation& sim, bool verifyChecksum) {
  StateAccess::State s = StateAccess::parse(bytes, sim, verifyChecksum);
  std::vector<double> extra = std::move(s.extra);
  StateAccess::apply(std::move(s), sim);
  return extra;
}

void saveState(const std::string& path, const Simulation& sim, const std::vector<double>& extra) {
  const std::string bytes = encodeState(sim, extra);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out)
    throw InputError(path + ": cannot write the state file");
  out.write(bytes.data(), std::streamsize(bytes.size()));
  out.flush();
  if (!out)
    throw InputError(path + ": writing the state file failed (disk full?)");
}

std::vector<double> loadState(const std::string& path, Simulation& sim) {
  std::string bytes;
  try {
    std::ifstream in(path, std::ios::binary);
    if (!in)
      throw StateError(path + ": cannot read the state file");
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (in.bad())
      throw StateError(path + ": reading the state file failed");
  } catch (const std::ios_base::failure& e) {
    // libstdc++ throws from the stream buffer for a folder (EISDIR) even without exceptions() set
    throw StateError(path + ": cannot read the state file (" + e.code().message() + ")");
  }
  try {
    return decodeState(bytes, sim);
  } catch (const StateError& e) {
    throw StateError(path + ": " + e.what());
  }
}

}  // namespace fp::sim
