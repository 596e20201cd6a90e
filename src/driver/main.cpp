// sinew: run a quasi-static scene described by a Teuchos XML parameter list.
#include <sinew/core/errors.hpp>
#include <sinew/driver/config.hpp>
#include <sinew/driver/info.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/driver/signals.hpp>

#include <Tpetra_Core.hpp>

#include <cstdlib>
#include <iostream>
#include <string>

namespace {

const char* kUsage =
    "usage: sinew [options] SCENE.xml\n"
    "\n"
    "Runs the quasi-static scene described by the Teuchos XML parameter list SCENE.xml\n"
    "(see inputs/ for shipped scenes and docs/ for the parameters).\n"
    "\n"
    "options:\n"
    "  --version, --info      print versions, Kokkos backends, threads, MPI ranks, HDF5, and exit\n"
    "  --check                read and validate SCENE.xml, print the configuration, and exit\n"
    "  --parameters           list every accepted XML entry with its default and meaning\n"
    "  --quiet                no progress lines\n"
    "  --output DIR           write results to DIR (overrides Output/Directory)\n"
    "  --restart FILE         continue the run from a checkpoint (DIR/checkpoint.h5) of the same scene\n"
    "  --kokkos-threads=N     OpenMP threads per rank (or set OMP_NUM_THREADS)\n"
    "  -h, --help             this text\n"
    "\n"
    "exit codes: 0 done, 1 error, 2 bad command line, 3 bad input, 4 a step did not converge,\n"
    "            128 + N stopped by signal N (SIGINT, SIGTERM) after writing a checkpoint\n";

int rank_of_world() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  // Spread OpenMP threads over cores unless the user chose otherwise (Kokkos warns when unset).
  setenv("OMP_PROC_BIND", "spread", 0);
  setenv("OMP_PLACES", "threads", 0);
  // Kokkos and MPI live exactly as long as this guard; no Kokkos/Tpetra object may outlive it.
  Tpetra::ScopeGuard scope(&argc, &argv);
  const bool root = rank_of_world() == 0;
  std::string scene_path;
  bool info = false, check = false, quiet = false;
  std::string restart, output;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--version" || a == "--info") {
      info = true;
    } else if (a == "--parameters") {
      if (root) std::cout << sinew::parameter_reference();
      return 0;
    } else if (a == "--check") {
      check = true;
    } else if (a == "--quiet") {
      quiet = true;
    } else if (a == "--restart" || a == "--output") {
      if (i + 1 >= argc) {
        if (root) std::cerr << "sinew: " << a << " needs a value\n";
        return 2;
      }
      (a == "--restart" ? restart : output) = argv[++i];
    } else if (a == "-h" || a == "--help") {
      if (root) std::cout << kUsage;
      return 0;
    } else if (!a.empty() && a[0] == '-') {
      if (root) std::cerr << "sinew: unknown option '" << a << "'\n\n" << kUsage;
      return 2;
    } else if (scene_path.empty()) {
      scene_path = a;
    } else {
      if (root) std::cerr << "sinew: more than one scene file given ('" << scene_path << "', '" << a << "')\n";
      return 2;
    }
  }
  if (info) {
    if (root) std::cout << sinew::build_info();
    return 0;
  }
  if (scene_path.empty()) {
    if (root) std::cout << kUsage;
    return 2;
  }
  try {
    sinew::SceneConfig scene = sinew::read_scene(scene_path);
    if (!output.empty()) scene.params->sublist("Output").set("Directory", output);
    if (check) {
      if (root) std::cout << "Sinew: " << sinew::execution_space_summary() << "\n" << sinew::describe(scene);
      return 0;
    }
    sinew::install_signal_handlers();
    return sinew::run_scene(scene, sinew::RunOptions{quiet, restart});
  } catch (const sinew::InputError& e) {
    if (root) std::cerr << "sinew: input error [" << sinew::to_string(e.kind) << "]: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    if (root) std::cerr << "sinew: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
