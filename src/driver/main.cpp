// sinew: run a quasi-static scene described by a Teuchos XML parameter list. The command line is
// checked completely before MPI and Kokkos start, so that a bad value is a message and exit code 2,
// never a crash inside a library.
#include <sinew/core/errors.hpp>
#include <sinew/driver/config.hpp>
#include <sinew/core/exit_codes.hpp>
#include <sinew/driver/info.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/driver/signals.hpp>

#include <Tpetra_Core.hpp>

#include <cerrno>
#include <cstring>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include <sched.h>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <unistd.h>

namespace {

const char* kUsage =
    "usage: sinew [options] SCENE.xml\n"
    "\n"
    "Runs the quasi-static scene described by the Teuchos XML parameter list SCENE.xml\n"
    "(see inputs/ for shipped scenes; sinew --parameters lists every entry).\n"
    "\n"
    "options:\n"
    "  --version, --info      print versions, Kokkos backends, threads, MPI ranks, HDF5, and exit\n"
    "  --check                read and validate SCENE.xml, print the configuration, and exit\n"
    "  --parameters           list every accepted XML entry with its default and meaning\n"
    "  --quiet                no progress lines\n"
    "  --output DIR           write results to DIR (overrides Output/Directory)\n"
    "  --restart FILE         continue the run from a checkpoint (DIR/checkpoint.h5) of the same scene\n"
    "  --restart-anyway FILE  the same from a checkpoint whose mesh, material, loading, skeleton, contact\n"
    "                         or time sections differ from the scene's (Solver and Output may always differ)\n"
    "  --kokkos-threads=N     OpenMP threads per rank, 1 to 4096 (or set OMP_NUM_THREADS)\n"
    "  -h, --help             this text\n"
    "\n"
    "exit codes: 0 done, 1 error, 2 bad command line, 3 bad input, 4 a step did not converge,\n"
    "            128 + N stopped by signal N (SIGINT, SIGTERM) after writing a checkpoint;\n"
    "            a second SIGINT/SIGTERM exits at once (the last checkpoint stays)\n";

struct CommandLine {
  std::string scene, restart, output;
  bool info = false, check = false, quiet = false, help = false, parameters = false, anyway = false;
};

// The rank the MPI launcher gave this process, before MPI is initialized (so only one prints).
bool launcher_rank_zero() {
  for (const char* v : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"})
    if (const char* r = std::getenv(v)) return std::string(r) == "0";
  return true;
}

bool positive_int(const std::string& s, long lo, long hi) {
  if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 9) return false;
  const long v = std::strtol(s.c_str(), nullptr, 10);
  return v >= lo && v <= hi;
}

// Returns "" when the command line is good, else why not.
std::string parse(int argc, char** argv, CommandLine& cl) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--version" || a == "--info") {
      cl.info = true;
    } else if (a == "--parameters") {
      cl.parameters = true;
    } else if (a == "--check") {
      cl.check = true;
    } else if (a == "--quiet") {
      cl.quiet = true;
    } else if (a == "-h" || a == "--help") {
      cl.help = true;
    } else if (a == "--restart" || a == "--restart-anyway" || a == "--output") {
      if (i + 1 >= argc || argv[i + 1][0] == '\0') return a + " needs a value";
      (a == "--output" ? cl.output : cl.restart) = argv[++i];
      if (a == "--restart-anyway") cl.anyway = true;
    } else if (a.rfind("--kokkos-threads=", 0) == 0 || a.rfind("--kokkos-num-threads=", 0) == 0) {
      const std::string v = a.substr(a.find('=') + 1);
      if (!positive_int(v, 1, 4096)) return "'" + a + "': the number of threads must be a whole number from 1 to 4096";
    } else if (a == "--kokkos-threads" || a == "--kokkos-num-threads") {
      return "'" + a + "' needs a value: " + a + "=N";
    } else if (!a.empty() && a[0] == '-') {
      return "unknown option '" + a + "'";
    } else if (cl.scene.empty()) {
      cl.scene = a;
    } else {
      return "more than one scene file given ('" + cl.scene + "', '" + a + "')";
    }
  }
  // Kokkos and the OpenMP runtime read these; a bad value must not reach them.
  for (const char* var : {"OMP_NUM_THREADS", "KOKKOS_NUM_THREADS"})
    if (const char* v = std::getenv(var)) {
      const std::string s = v;
      const std::string first = s.substr(0, s.find(','));  // OMP_NUM_THREADS may list nesting levels
      if (!positive_int(first, 1, 4096))
        return std::string(var) + "='" + s + "' is not a number of threads from 1 to 4096";
    }
  if (!cl.help && !cl.parameters && !cl.info && cl.scene.empty()) return "no scene file given";
  return "";
}

}  // namespace

// Transparent huge pages for malloc's large chunks (glibc's tunable glibc.malloc.hugetlb=1, which
// advises the kernel for them; Debian's kernels default to THP 'madvise'). Every MueLu setup from
// scratch allocates about 1.7 kB per DOF anew, and on 4 kB pages first touching them is much of its
// cost: the 969k-DOF stretch's first step (MueLu's first setup and one update), three alternating runs
// each, MueLu 16.9 / 20.6 / 21.9 s -> 11.7 / 13.5 / 13.7 s, the step 35.4 / 42.8 / 44.5 s -> 28.9 / 36.0 /
// 33.9 s, the same peak memory. glibc reads its tunables only at start, so the process executes itself
// once with the tunable added, before MPI or Kokkos start (same PID, arguments and environment).
// SINEW_HUGE_PAGES=0, or a GLIBC_TUNABLES that already sets it, leaves the process as it is; a failed
// exec carries on without. The new image parses the same command line again.
static void request_huge_pages(char** argv) {
  const char* opt = std::getenv("SINEW_HUGE_PAGES");
  if (opt && std::strcmp(opt, "0") == 0) return;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  const std::string current = tunables ? tunables : "";
  if (current.find("glibc.malloc.hugetlb") != std::string::npos) return;
  const std::string wanted = current.empty() ? "glibc.malloc.hugetlb=1" : current + ":glibc.malloc.hugetlb=1";
  // With OMP_PROC_BIND set, libgomp bound this thread to its first place when it was loaded; exec keeps
  // that one-CPU mask and the new image would then put every thread on it (measured: the step took twice
  // as long). The union of the places is the mask the process started with: give it back first.
  cpu_set_t all;
  CPU_ZERO(&all);
  int cpus = 0;
#ifdef _OPENMP
  for (int place = 0; place < omp_get_num_places(); ++place) {
    std::vector<int> ids(static_cast<std::size_t>(omp_get_place_num_procs(place)));
    if (ids.empty()) continue;
    omp_get_place_proc_ids(place, ids.data());
    for (int id : ids)
      if (id >= 0 && id < CPU_SETSIZE) {
        CPU_SET(id, &all);
        ++cpus;
      }
  }
#endif
  if (cpus > 0 && sched_setaffinity(0, sizeof(all), &all) != 0) return;
  if (setenv("GLIBC_TUNABLES", wanted.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
  // Only on failure: the environment goes back to what it was.
  if (tunables)
    setenv("GLIBC_TUNABLES", current.c_str(), 1);
  else
    unsetenv("GLIBC_TUNABLES");
}

int main(int argc, char** argv) {
  using sinew::ExitCode;
  CommandLine cl;
  const std::string bad = parse(argc, argv, cl);
  const bool speaker = launcher_rank_zero();
  if (!bad.empty()) {
    // One line that says what is wrong and where to look, not a page of usage to scroll past.
    if (speaker) std::cerr << "sinew: " << bad << " (see 'sinew --help')\n";
    return sinew::code(ExitCode::Usage);
  }
  if (cl.help) {
    if (speaker) std::cout << kUsage;
    return 0;
  }
  if (cl.parameters) {
    if (speaker) std::cout << sinew::parameter_reference();
    return 0;
  }
  // Only a run allocates enough to gain from huge pages; the exec costs about 0.08 s of loading.
  if (!cl.info && !cl.check) request_huge_pages(argv);
  // Spread OpenMP threads over cores unless the user chose otherwise (Kokkos warns when unset).
  setenv("OMP_PROC_BIND", "spread", 0);
  setenv("OMP_PLACES", "threads", 0);
  // Kokkos and MPI live exactly as long as this guard; no Kokkos/Tpetra object may outlive it.
  Tpetra::ScopeGuard scope(&argc, &argv);
  const bool root = Tpetra::getDefaultComm()->getRank() == 0;
  if (cl.info) {
    if (root) std::cout << sinew::build_info();
    return 0;
  }
  return sinew::run_guarded("sinew", root, [&] {
    sinew::SceneConfig scene = sinew::read_scene(cl.scene);
    if (!cl.output.empty()) scene.params.output.directory = cl.output;
    if (cl.check) {
      sinew::check_mesh_file(scene);
      const std::string joints = sinew::describe_joints(scene);  // collective: builds the lattice
      if (root) std::cout << "Sinew: " << sinew::execution_space_summary() << "\n" << sinew::describe(scene) << joints;
      return 0;
    }
    sinew::install_signal_handlers();
    sinew::RunOptions options;
    options.quiet = cl.quiet;
    options.restart_file = cl.restart;
    options.restart_anyway = cl.anyway;
    sinew::Simulation sim(scene, options);
    return sim.run();
  });
}
