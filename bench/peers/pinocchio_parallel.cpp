// Pinocchio's answer to many states per call: abaInParallel (OpenMP, one state per thread, a ModelPool
// holding one Data per thread), timed over a batch of random states for 1 and 2 threads (issue 13: "report
// the speedup ... over Pinocchio's OpenMP abaInParallel on this 2-core machine").
//
// Usage: pinocchio_parallel [--floating] [--states N] [--repeats R] URDF
// Prints one JSON object on stdout: {"model", "floating", "states", "aba_serial", "aba_parallel_1",
// "aba_parallel_2"}, each in ns per state (median over the repeats); "aba_serial" is a plain loop of
// pinocchio::aba over the same states, the baseline of the parallel calls' overhead.
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/parallel/aba.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/multibody/pool.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

double g_checksum = 0.0;

template <typename F>
double median_ns_per_state(int repeats, int states, F&& f) {
  std::vector<double> times;
  times.reserve(repeats);
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    f();
    const auto end = std::chrono::steady_clock::now();
    times.push_back(std::chrono::duration<double, std::nano>(end - start).count() / states);
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  return times[times.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  bool floating = false;
  int states = 1024;
  int repeats = 201;
  std::string urdf;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--floating") {
      floating = true;
    } else if ((arg == "--states" || arg == "--repeats") && i + 1 < argc) {
      const int n = std::atoi(argv[++i]);
      if (n <= 0) {
        std::fprintf(stderr, "%s needs a positive number\n", arg.c_str());
        return 2;
      }
      (arg == "--states" ? states : repeats) = n;
    } else if (!arg.empty() && arg[0] != '-' && urdf.empty()) {
      urdf = arg;
    } else {
      std::fprintf(stderr, "usage: %s [--floating] [--states N] [--repeats R] URDF\n", argv[0]);
      return 2;
    }
  }
  if (urdf.empty()) {
    std::fprintf(stderr, "usage: %s [--floating] [--states N] [--repeats R] URDF\n", argv[0]);
    return 2;
  }
  pinocchio::Model model;
  if (floating) {
    pinocchio::urdf::buildModel(urdf, pinocchio::JointModelFreeFlyer(), model);
  } else {
    pinocchio::urdf::buildModel(urdf, model);
  }
  // Random states within the limits (bounded where the URDF leaves a joint unbounded).
  model.lowerPositionLimit = model.lowerPositionLimit.cwiseMax(-3.0);
  model.upperPositionLimit = model.upperPositionLimit.cwiseMin(3.0);
  std::srand(20240601u);
  Eigen::MatrixXd q(model.nq, states), v(model.nv, states), tau(model.nv, states), a(model.nv, states);
  for (int s = 0; s < states; ++s) {
    q.col(s) = pinocchio::randomConfiguration(model);
    v.col(s) = Eigen::VectorXd::Random(model.nv);
    tau.col(s) = Eigen::VectorXd::Random(model.nv);
  }
  pinocchio::Data data(model);
  const double serial = median_ns_per_state(repeats, states, [&] {
    for (int s = 0; s < states; ++s) {
      a.col(s) = pinocchio::aba(model, data, q.col(s), v.col(s), tau.col(s));
    }
    g_checksum += a(0, 0);
  });
  pinocchio::ModelPool pool(model, 2);
  double parallel[2] = {0, 0};
  for (int threads = 1; threads <= 2; ++threads) {
    parallel[threads - 1] = median_ns_per_state(repeats, states, [&] {
      pinocchio::abaInParallel(static_cast<size_t>(threads), pool, q, v, tau, a);
      g_checksum += a(0, 0);
    });
  }
  std::string stem = urdf.substr(urdf.find_last_of('/') + 1);
  stem = stem.substr(0, stem.find('.'));
  std::printf(
      "{\"model\": \"%s\", \"floating\": %s, \"states\": %d, \"aba_serial\": %.1f, \"aba_parallel_1\": %.1f, "
      "\"aba_parallel_2\": %.1f}\n",
      stem.c_str(), floating ? "true" : "false", states, serial, parallel[0], parallel[1]);
  std::fprintf(stderr, "checksum %g\n", g_checksum);
  return 0;
}
