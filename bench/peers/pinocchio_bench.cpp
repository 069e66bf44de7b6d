// Pinocchio peer benchmark for embedyn.
//
// Usage: pinocchio_bench [--floating] [--repeats N] [--batch B] [--frame LINK] [--wrenches A,B,…]
//                        [--derivatives] URDF...
//
// With --frame: also times the frame Jacobian with its bias (computeFrameJacobian in
// LOCAL_WORLD_ALIGNED, then forwardKinematics(q, v, 0) and getFrameClassicalAcceleration), and the
// centre of mass and centroidal momentum (jacobianCenterOfMass, ccrba, dccrba). With --wrenches:
// aba with a wrench on each of those links (moved into its joint's frame inside the timed call, as a
// caller holding link-frame wrenches must). With --derivatives: computeABADerivatives and
// computeRNEADerivatives (Carpentier and Mansard's analytical derivatives).
//
// For every URDF: build the Pinocchio model (free-flyer root with --floating, fixed base
// otherwise), pre-generate kStates random states, then time aba, rnea, crba and
// computeMinverse while cycling through the states. Each repeat (default 1001) times a batch of
// calls with std::chrono::steady_clock and divides by the batch size (default: calibrated to
// ~0.2 ms per batch, 10..1000 calls; --batch B fixes it); the reported figure is the median over
// the repeats, in ns per call. One JSON object per URDF is printed on its own line on stdout;
// diagnostics (convention used, spread, checksum) go to stderr.
//
// Build: bench/peers/build_pinocchio.sh (header-only use of Pinocchio's algorithms, -O3, no
// -march=native; the URDF parser comes from the wheel's prebuilt libpinocchio_parsers).

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/center-of-mass.hpp>
#include <pinocchio/algorithm/centroidal.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/config.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

namespace {

constexpr int kStates = 64;
constexpr unsigned kSeed = 20240601u;
constexpr double kBatchTargetNs = 200e3;  // 0.2 ms per timed batch unless --batch is given
const char* const kPinocchioVersion = PINOCCHIO_VERSION;  // from pinocchio/config.hpp

struct Options {
  bool floating = false;
  int repeats = 1001;
  int batch = 0;  // 0: calibrate per algorithm to about kBatchTargetNs per batch
  std::string frame;                  // --frame: time its Jacobian and bias, com and centroidal
  std::vector<std::string> wrenches;  // --wrenches: time aba with a wrench on each of these links
  bool derivatives = false;           // --derivatives: time the analytical derivatives
  std::vector<std::string> urdfs;
};

struct States {
  std::vector<Eigen::VectorXd> q, v, tau, a;
};

struct Stats {
  double median = 0, min = 0, max = 0;
  double cpu_wall = 0;  // process CPU time / wall time over all timed batches (1.0 = never preempted)
  int batch = 0;        // calls per timed batch
};

// Checksum sink: every timed call feeds one output element into it, so the compiler cannot
// drop the work; the total is printed to stderr at the end.
double g_checksum = 0.0;

void usage(const char* argv0) {
  std::fprintf(stderr, "usage: %s [--floating] [--repeats N] [--batch B] [--frame LINK] [--wrenches A,B,...] [--derivatives] URDF...\n", argv0);
}

bool parse_args(int argc, char** argv, Options& opt) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--floating") {
      opt.floating = true;
    } else if (arg == "--repeats" || arg == "--batch") {
      if (i + 1 >= argc) return false;
      const int n = std::atoi(argv[++i]);
      if (n <= 0) return false;  // --batch must be explicit and positive; omit it for auto
      (arg == "--repeats" ? opt.repeats : opt.batch) = n;
    } else if (arg == "--frame") {
      if (i + 1 >= argc) return false;
      opt.frame = argv[++i];
    } else if (arg == "--wrenches") {
      if (i + 1 >= argc) return false;
      std::string list = argv[++i];
      std::size_t start = 0;
      while (start <= list.size()) {
        const std::size_t comma = list.find(',', start);
        const std::size_t end = comma == std::string::npos ? list.size() : comma;
        if (end > start) opt.wrenches.push_back(list.substr(start, end - start));
        start = end + 1;
      }
    } else if (arg == "--derivatives") {
      opt.derivatives = true;
    } else if (arg == "-h" || arg == "--help") {
      return false;
    } else if (!arg.empty() && arg[0] == '-') {
      std::fprintf(stderr, "unknown option %s\n", arg.c_str());
      return false;
    } else {
      opt.urdfs.push_back(arg);
    }
  }
  return !opt.urdfs.empty();
}

std::string path_stem(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::size_t dot = name.find_last_of('.');
  if (dot != std::string::npos && dot > 0) name.resize(dot);
  return name;
}

// randomConfiguration samples uniformly between the position limits and throws on infinite
// ones. Give the free-flyer translation ±1 m and every other unbounded coordinate ±π.
void bound_limits(pinocchio::Model& model) {
  const double pi = 3.14159265358979323846;
  for (pinocchio::JointIndex j = 1; j < static_cast<pinocchio::JointIndex>(model.njoints); ++j) {
    const auto& jm = model.joints[j];
    const int iq = jm.idx_q();
    if (jm.shortname() == "JointModelFreeFlyer") {
      for (int k = 0; k < 3; ++k) {
        model.lowerPositionLimit[iq + k] = -1.0;
        model.upperPositionLimit[iq + k] = 1.0;
      }
      for (int k = 3; k < 7; ++k) {  // quaternion: sampled uniformly on S3 regardless
        model.lowerPositionLimit[iq + k] = -1.0;
        model.upperPositionLimit[iq + k] = 1.0;
      }
      continue;
    }
    for (int k = 0; k < jm.nq(); ++k) {
      double& lo = model.lowerPositionLimit[iq + k];
      double& hi = model.upperPositionLimit[iq + k];
      if (!std::isfinite(lo) || std::fabs(lo) > 1e10) lo = -pi;
      if (!std::isfinite(hi) || std::fabs(hi) > 1e10) hi = pi;
    }
  }
}

States make_states(const pinocchio::Model& model) {
  std::srand(kSeed);  // Pinocchio and Eigen's Random() both draw from std::rand
  States s;
  for (int i = 0; i < kStates; ++i) {
    s.q.push_back(pinocchio::randomConfiguration(model));
    s.v.push_back(Eigen::VectorXd::Random(model.nv));    // uniform in [-1, 1]
    s.tau.push_back(Eigen::VectorXd::Random(model.nv));
    s.a.push_back(Eigen::VectorXd::Random(model.nv));
  }
  return s;
}

// Times `call(state_index, call_index)` in `repeats` batches; returns ns per call.
// Batch size: --batch N if given, else calibrated so one batch lasts about kBatchTargetNs.
// Short batches matter on a shared machine: a batch longer than a scheduler time slice (a few ms)
// is almost always cut by preemption when another task shares the core, and then the median is
// inflated too; with ~0.2 ms batches the preempted ones are a minority that the median ignores.
template <typename F>
Stats time_it(const Options& opt, F&& call) {
  using clock = std::chrono::steady_clock;
  // Warm-up (caches, branch predictors, frequency ramp) that also calibrates the batch size.
  int batch = opt.batch;
  {
    int n = 0;
    const auto t0 = clock::now();
    double elapsed = 0;
    while (n < 20000 && (n < 100 || elapsed < 2e6)) {
      call(n % kStates, n);
      ++n;
      if (n % 16 == 0) elapsed = std::chrono::duration<double, std::nano>(clock::now() - t0).count();
    }
    elapsed = std::chrono::duration<double, std::nano>(clock::now() - t0).count();
    if (batch <= 0) {
      const double per_call = elapsed / n;
      batch = static_cast<int>(std::lround(kBatchTargetNs / per_call));
      batch = std::max(10, std::min(batch, 1000));
    }
  }
  std::vector<double> per_call(opt.repeats);
  int k = 0;
  const std::clock_t cpu0 = std::clock();
  const auto wall0 = clock::now();
  for (int r = 0; r < opt.repeats; ++r) {
    const auto t0 = clock::now();
    for (int b = 0; b < batch; ++b, ++k) call(k % kStates, k);
    const auto t1 = clock::now();
    per_call[r] = std::chrono::duration<double, std::nano>(t1 - t0).count() / batch;
  }
  const double cpu_s = double(std::clock() - cpu0) / CLOCKS_PER_SEC;
  const double wall_s = std::chrono::duration<double>(clock::now() - wall0).count();
  std::sort(per_call.begin(), per_call.end());
  Stats st;
  st.cpu_wall = wall_s > 0 ? cpu_s / wall_s : 1.0;
  st.batch = batch;
  st.min = per_call.front();
  st.max = per_call.back();
  const std::size_t n = per_call.size();
  st.median = n % 2 ? per_call[n / 2] : 0.5 * (per_call[n / 2 - 1] + per_call[n / 2]);
  return st;
}

// Untimed sanity line on stderr: a model corrupted at load time (e.g. Eigen alignment mismatch
// with the prebuilt parser) shows up as a wrong mass, a non-zero residual or NaNs.
void sanity_check(const pinocchio::Model& model, pinocchio::Data& data, const States& s) {
  using pinocchio::Convention;
  const double mass = pinocchio::computeTotalMass(model);
  const Eigen::VectorXd q0 = pinocchio::neutral(model);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.nv);
  const double fall = pinocchio::aba(model, data, q0, zero, zero, Convention::WORLD).norm();
  const Eigen::VectorXd qdd = pinocchio::aba(model, data, s.q[0], s.v[0], s.tau[0], Convention::WORLD);
  const Eigen::VectorXd nle = pinocchio::rnea(model, data, s.q[0], s.v[0], zero);
  pinocchio::crba(model, data, s.q[0], Convention::LOCAL);
  Eigen::MatrixXd M = data.M;
  M.triangularView<Eigen::StrictlyLower>() = M.transpose().triangularView<Eigen::StrictlyLower>();
  const double residual = (M * qdd + nle - s.tau[0]).lpNorm<Eigen::Infinity>();
  pinocchio::computeMinverse(model, data, s.q[0]);
  Eigen::MatrixXd Minv = data.Minv;
  Minv.triangularView<Eigen::StrictlyLower>() = Minv.transpose().triangularView<Eigen::StrictlyLower>();
  const double inv_err = (M * Minv - Eigen::MatrixXd::Identity(model.nv, model.nv)).lpNorm<Eigen::Infinity>();
  std::fprintf(stderr, "  check: mass %.6f kg, |aba(neutral,0,0)| %.9g, |M qdd + nle - tau| %.2e, |M Minv - I| %.2e\n",
               mass, fall, residual, inv_err);
}

void report_stats(const std::string& model, const char* algo, const Stats& st) {
  std::fprintf(stderr, "  %-16s %-10s median %9.1f  min %9.1f  max %9.1f ns  batch %4d  cpu/wall %.2f\n",
               model.c_str(), algo, st.median, st.min, st.max, st.batch, st.cpu_wall);
}

int run_one(const Options& opt, const std::string& path) {
  pinocchio::Model model;
  try {
    if (opt.floating)
      pinocchio::urdf::buildModel(path, pinocchio::JointModelFreeFlyer(), model);
    else
      pinocchio::urdf::buildModel(path, model);  // mimic=false: mimic joints stay independent
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: cannot build model: %s\n", path.c_str(), e.what());
    return 1;
  }
  model.gravity.linear(Eigen::Vector3d(0.0, 0.0, -9.81));
  bound_limits(model);
  pinocchio::Data data(model);
  const States s = make_states(model);
  const int nv = model.nv;
  const std::string stem = path_stem(path);
  using pinocchio::Convention;

  std::fprintf(stderr, "%s (%s): nq=%d nv=%d njoints=%d, aba convention WORLD (LOCAL also timed)\n",
               path.c_str(), opt.floating ? "floating" : "fixed", model.nq, nv, model.njoints);
  sanity_check(model, data, s);

  const Stats aba = time_it(opt, [&](int i, int k) {
    pinocchio::aba(model, data, s.q[i], s.v[i], s.tau[i], Convention::WORLD);
    g_checksum += data.ddq[k % nv];
  });
  const Stats aba_local = time_it(opt, [&](int i, int k) {
    pinocchio::aba(model, data, s.q[i], s.v[i], s.tau[i], Convention::LOCAL);
    g_checksum += data.ddq[k % nv];
  });
  const Stats rnea = time_it(opt, [&](int i, int k) {
    pinocchio::rnea(model, data, s.q[i], s.v[i], s.a[i]);
    g_checksum += data.tau[k % nv];
  });
  const Stats crba = time_it(opt, [&](int i, int k) {
    pinocchio::crba(model, data, s.q[i], Convention::LOCAL);
    g_checksum += data.M(0, k % nv);
  });
  const Stats crba_world = time_it(opt, [&](int i, int k) {
    pinocchio::crba(model, data, s.q[i], Convention::WORLD);
    g_checksum += data.M(0, k % nv);
  });
  // crba fills the upper triangle of data.M only (the entries of joints on different branches are never
  // written); embedyn's crba writes all of M. The same output as ours: crba, then the lower triangle.
  const Stats crba_full = time_it(opt, [&](int i, int k) {
    pinocchio::crba(model, data, s.q[i], Convention::LOCAL);
    data.M.triangularView<Eigen::StrictlyLower>() = data.M.transpose().triangularView<Eigen::StrictlyLower>();
    g_checksum += data.M(k % nv, 0);
  });
  const Stats minv = time_it(opt, [&](int i, int k) {
    pinocchio::computeMinverse(model, data, s.q[i]);
    g_checksum += data.Minv(0, k % nv);
  });

  report_stats(stem, "aba/WORLD", aba);
  report_stats(stem, "aba/LOCAL", aba_local);
  report_stats(stem, "rnea", rnea);
  report_stats(stem, "crba/LOCAL", crba);
  report_stats(stem, "crba/WORLD", crba_world);
  report_stats(stem, "crba+lower", crba_full);
  report_stats(stem, "minv", minv);
  double cpu_wall = 1.0;
  for (const Stats* st : {&aba, &aba_local, &rnea, &crba, &crba_world, &minv})
    cpu_wall = std::min(cpu_wall, st->cpu_wall);

  // Contacts, frames and momentum (only when asked for).
  std::string extra;
  char buf[256];
  if (!opt.frame.empty()) {
    if (!model.existFrame(opt.frame)) {
      std::fprintf(stderr, "%s: no frame %s\n", path.c_str(), opt.frame.c_str());
      return 1;
    }
    const pinocchio::FrameIndex fid = model.getFrameId(opt.frame);
    pinocchio::Data::Matrix6x J = pinocchio::Data::Matrix6x::Zero(6, nv);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(nv);
    const Stats jac = time_it(opt, [&](int i, int k) {
      pinocchio::computeFrameJacobian(model, data, s.q[i], fid, pinocchio::LOCAL_WORLD_ALIGNED, J);
      pinocchio::forwardKinematics(model, data, s.q[i], s.v[i], zero);
      const auto bias = pinocchio::getFrameClassicalAcceleration(model, data, fid, pinocchio::LOCAL_WORLD_ALIGNED);
      g_checksum += J(k % 6, k % nv) + bias.linear()[k % 3];
    });
    const Stats jcom = time_it(opt, [&](int i, int k) {
      pinocchio::jacobianCenterOfMass(model, data, s.q[i]);
      g_checksum += data.Jcom(k % 3, k % nv);
    });
    const Stats ccrba = time_it(opt, [&](int i, int k) {
      pinocchio::ccrba(model, data, s.q[i], s.v[i]);
      g_checksum += data.Ag(k % 6, k % nv) + data.hg.linear()[k % 3];
    });
    const Stats dccrba = time_it(opt, [&](int i, int k) {
      pinocchio::dccrba(model, data, s.q[i], s.v[i]);
      g_checksum += (data.dAg * s.v[i])[k % 6];
    });
    report_stats(stem, "frame_jac", jac);
    report_stats(stem, "jcom", jcom);
    report_stats(stem, "ccrba", ccrba);
    report_stats(stem, "dccrba", dccrba);
    std::snprintf(buf, sizeof buf,
                  ", \"frame\": \"%s\", \"frame_jacobian_bias\": %.1f, \"com_jacobian\": %.1f, "
                  "\"ccrba\": %.1f, \"dccrba\": %.1f",
                  opt.frame.c_str(), jac.median, jcom.median, ccrba.median, dccrba.median);
    extra += buf;
  }
  if (!opt.wrenches.empty()) {
    std::vector<pinocchio::FrameIndex> fids;
    for (const auto& name : opt.wrenches) {
      if (!model.existFrame(name)) {
        std::fprintf(stderr, "%s: no frame %s\n", path.c_str(), name.c_str());
        return 1;
      }
      fids.push_back(model.getFrameId(name));
    }
    // One link-frame wrench per state and link (random, fixed before timing).
    std::vector<std::vector<pinocchio::Force>> link_wrenches(kStates);
    for (auto& w : link_wrenches)
      for (std::size_t l = 0; l < fids.size(); ++l) w.push_back(pinocchio::Force(Eigen::Matrix<double, 6, 1>::Random() * 20.0));
    std::vector<pinocchio::Force> fext(model.njoints, pinocchio::Force::Zero());
    const Stats aba_fext = time_it(opt, [&](int i, int k) {
      for (auto& f : fext) f.setZero();
      for (std::size_t l = 0; l < fids.size(); ++l) {
        const auto& frame = model.frames[fids[l]];
        fext[frame.parentJoint] += frame.placement.act(link_wrenches[i][l]);
      }
      pinocchio::aba(model, data, s.q[i], s.v[i], s.tau[i], fext, Convention::WORLD);
      g_checksum += data.ddq[k % nv];
    });
    report_stats(stem, "aba_fext", aba_fext);
    std::snprintf(buf, sizeof buf, ", \"aba_fext\": %.1f, \"wrench_links\": %zu", aba_fext.median, fids.size());
    extra += buf;
  }

  if (opt.derivatives) {
    const Stats aba_d = time_it(opt, [&](int i, int k) {
      pinocchio::computeABADerivatives(model, data, s.q[i], s.v[i], s.tau[i]);
      g_checksum += data.ddq_dq(k % nv, (k / nv) % nv) + data.Minv(0, k % nv);
    });
    const Stats rnea_d = time_it(opt, [&](int i, int k) {
      pinocchio::computeRNEADerivatives(model, data, s.q[i], s.v[i], s.a[i]);
      g_checksum += data.dtau_dq(k % nv, (k / nv) % nv) + data.M(0, k % nv);
    });
    report_stats(stem, "aba_derivatives", aba_d);
    report_stats(stem, "rnea_derivatives", rnea_d);
    std::snprintf(buf, sizeof buf, ", \"aba_derivatives\": %.1f, \"rnea_derivatives\": %.1f", aba_d.median,
                  rnea_d.median);
    extra += buf;
  }

  std::printf(
      "{\"model\": \"%s\", \"floating\": %s, \"nq\": %d, \"nv\": %d, \"aba\": %.1f, \"rnea\": %.1f, "
      "\"crba\": %.1f, \"minv\": %.1f, \"aba_convention\": \"WORLD\", \"aba_local\": %.1f, "
      "\"crba_world\": %.1f, \"crba_full\": %.1f, \"cpu_wall_min\": %.2f, \"repeats\": %d, "
      "\"batch_aba\": %d, \"pinocchio\": \"%s\"%s}\n",
      stem.c_str(), opt.floating ? "true" : "false", model.nq, nv, aba.median, rnea.median,
      crba.median, minv.median, aba_local.median, crba_world.median, crba_full.median, cpu_wall,
      opt.repeats, aba.batch,
      kPinocchioVersion, extra.c_str());
  std::fflush(stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  if (!parse_args(argc, argv, opt)) {
    usage(argv[0]);
    return 2;
  }
  int failures = 0;
  for (const auto& path : opt.urdfs) failures += run_one(opt, path);
  std::fprintf(stderr, "checksum %.17g\n", g_checksum);
  return failures ? 1 : 0;
}
