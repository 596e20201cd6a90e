// Output: collective parallel HDF5 with checked closes, durable renames, and failures agreed on by all
// ranks; the XDMF index; the CSV log; checkpoints that record where the load path stood.
#include <sinew/core/collective.hpp>
#include <sinew/core/errors.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/io/output.hpp>

#include "durable_file.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_MultiVector.hpp>
#include <Tpetra_Vector.hpp>
#include <hdf5.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <iomanip>
#include <regex>
#include <sstream>

namespace sinew {

namespace fs = std::filesystem;

using io_detail::replace_durably;
using io_detail::sync_path;

namespace {

double wall_clock() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// HDF5 handle; close() reports a failure (a flush that did not reach the disk), the destructor only
// cleans up on error paths.
class H5 {
 public:
  H5(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(id), close_(close), what_(what) {
    if (id_ < 0) throw std::runtime_error("HDF5: " + what + " failed");
  }
  ~H5() {
    if (id_ >= 0) close_(id_);
  }
  H5(const H5&) = delete;
  H5& operator=(const H5&) = delete;
  hid_t id() const { return id_; }
  void close() {
    const herr_t r = close_(id_);
    id_ = -1;
    if (r < 0) throw std::runtime_error("HDF5: closing " + what_ + " failed");
  }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
  std::string what_;
};

// Silences HDF5's own error printing while reading a file that may be bad (we report errors ourselves),
// and restores the previous handler afterwards.
class QuietHdf5 {
 public:
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

void check(herr_t r, const std::string& what) {
  if (r < 0) throw std::runtime_error("HDF5: " + what + " failed");
}

// Collective write of rows [first, first + count) of a rows x cols dataset.
template <class T>
void write_rows(hid_t file, const std::string& name, hid_t type, long long rows, int cols, long long first,
                long long count, const T* data, const std::string& fname) {
  hsize_t dims[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(cols)};
  const int rank = cols == 1 ? 1 : 2;
  H5 space(H5Screate_simple(rank, dims, nullptr), H5Sclose, fname + ": dataspace " + name);
  H5 dset(H5Dcreate2(file, name.c_str(), type, space.id(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
          fname + ": create " + name);
  hsize_t start[2] = {static_cast<hsize_t>(first), 0}, cnt[2] = {static_cast<hsize_t>(count), static_cast<hsize_t>(cols)};
  H5 mem(H5Screate_simple(rank, cnt, nullptr), H5Sclose, fname + ": memspace " + name);
  if (count > 0) {
    check(H5Sselect_hyperslab(space.id(), H5S_SELECT_SET, start, nullptr, cnt, nullptr), "selecting rows of " + name);
  } else {
    H5Sselect_none(space.id());
    H5Sselect_none(mem.id());
  }
  H5 dxpl(H5Pcreate(H5P_DATASET_XFER), H5Pclose, "transfer properties");
  H5Pset_dxpl_mpio(dxpl.id(), H5FD_MPIO_COLLECTIVE);
  check(H5Dwrite(dset.id(), type, mem.id(), space.id(), dxpl.id(), data), "writing " + name + " to " + fname);
  dset.close();
}

void write_attribute(hid_t file, const char* name, double value) {
  H5 space(H5Screate(H5S_SCALAR), H5Sclose, "attribute space");
  H5 attr(H5Acreate2(file, name, H5T_NATIVE_DOUBLE, space.id(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, "attribute");
  check(H5Awrite(attr.id(), H5T_NATIVE_DOUBLE, &value), std::string("writing attribute ") + name);
  attr.close();
}

void write_layout_attribute(hid_t file, const char* name, std::uint64_t value) {
  H5 space(H5Screate(H5S_SCALAR), H5Sclose, "attribute space");
  H5 attr(H5Acreate2(file, name, H5T_NATIVE_UINT64, space.id(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, "attribute");
  check(H5Awrite(attr.id(), H5T_NATIVE_UINT64, &value), std::string("writing attribute ") + name);
  attr.close();
}

void write_attribute(hid_t file, const char* name, const std::string& value) {
  H5 type(H5Tcopy(H5T_C_S1), H5Tclose, "string type");
  check(H5Tset_size(type.id(), std::max<std::size_t>(1, value.size())), "string size");
  H5 space(H5Screate(H5S_SCALAR), H5Sclose, "attribute space");
  H5 attr(H5Acreate2(file, name, type.id(), space.id(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, "attribute");
  check(H5Awrite(attr.id(), type.id(), value.c_str()), std::string("writing attribute ") + name);
  attr.close();
}

// A 1-D char dataset (written by write_rows) as a string, read whole by this rank.
std::string read_text(hid_t file, const std::string& name) {
  H5 dset(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose, "open " + name);
  H5 space(H5Dget_space(dset.id()), H5Sclose, "dataspace of " + name);
  if (H5Sget_simple_extent_ndims(space.id()) != 1) throw std::runtime_error("not a one-dimensional dataset");
  hsize_t n = 0;
  H5Sget_simple_extent_dims(space.id(), &n, nullptr);
  if (n > (hsize_t(1) << 26)) throw std::runtime_error("larger than 64 MB");
  std::string text(static_cast<std::size_t>(n), '\0');
  if (n > 0) check(H5Dread(dset.id(), H5T_NATIVE_CHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, text.data()), "reading " + name);
  return text;
}

// The "layout" attribute of a results file (read by one rank): which row order its rows follow, or
// nothing for a file that has none (written before layouts were recorded) or cannot be read.
std::optional<std::uint64_t> read_layout(const std::string& path) {
  QuietHdf5 quiet;
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) return std::nullopt;
  std::optional<std::uint64_t> out;
  if (H5Aexists(f, "layout") > 0) {
    const hid_t a = H5Aopen(f, "layout", H5P_DEFAULT);
    std::uint64_t v = 0;
    if (a >= 0 && H5Aread(a, H5T_NATIVE_UINT64, &v) >= 0) out = v;
    if (a >= 0) H5Aclose(a);
  }
  H5Fclose(f);
  return out;
}

// A digest of the output row order (collective): the owned nodes' and elements' global ids rank by
// rank, which is what the rows of mesh.h5 and of every step file follow. It differs between runs on
// different numbers of ranks (a mesh file's partition depends on them), so a restart can tell whether
// the mesh file on disk pairs with its new step files.
std::uint64_t layout_digest(const Mesh& m, MPI_Comm comm) {
  auto mix = [](std::uint64_t h, std::uint64_t v) {
    for (int b = 0; b < 8; ++b) h = (h ^ ((v >> (8 * b)) & 0xffu)) * 1099511628211ull;  // FNV-1a
    return h;
  };
  std::uint64_t h = 1469598103934665603ull;
  h = mix(h, m.n_owned_nodes);
  for (std::size_t n = 0; n < m.n_owned_nodes; ++n) h = mix(h, static_cast<std::uint64_t>(m.node_gid[n]));
  h = mix(h, m.n_owned_elements);
  for (std::size_t e = 0; e < m.n_owned_elements; ++e) h = mix(h, static_cast<std::uint64_t>(m.element_gid[e]));
  int P = 1, me = 0;
  MPI_Comm_size(comm, &P);
  MPI_Comm_rank(comm, &me);
  std::vector<std::uint64_t> all(P);
  MPI_Gather(&h, 1, MPI_UINT64_T, all.data(), 1, MPI_UINT64_T, 0, comm);
  std::uint64_t digest = 1469598103934665603ull;
  for (std::uint64_t v : all) digest = mix(digest, v);
  MPI_Bcast(&digest, 1, MPI_UINT64_T, 0, comm);
  return digest;
}

// Opens a CSV log for appending. A new run writes its header aside and renames it into place; a restart
// keeps the rows of the steps up to its checkpoint (a row written after it belongs to a step that will
// be computed again), also written aside and renamed, so that a crash during the restart leaves the old
// log whole.
void open_csv(std::ofstream& out, const std::string& path, int restart_step, const std::string& header) {
  std::vector<std::string> keep;
  if (restart_step >= 0) {
    std::ifstream old(path);
    std::string line;
    if (std::getline(old, line))
      while (std::getline(old, line))
        if (!line.empty() && line.back() != '\r' && std::atoi(line.c_str()) <= restart_step) keep.push_back(line);
  }
  const std::string tmp = path + ".tmp";
  {
    std::ofstream fresh(tmp, std::ios::trunc);
    if (!fresh) throw InputError("Output: cannot write " + tmp, InputErrorKind::File);
    fresh << header << "\n";
    for (const auto& l : keep) fresh << l << "\n";
    fresh.flush();
    if (!fresh) throw InputError("Output: writing " + tmp + " failed (disk full?)", InputErrorKind::File);
  }
  replace_durably(tmp, path);
  out.open(path, std::ios::app);
  if (!out) throw InputError("Output: cannot write " + path, InputErrorKind::File);
}

// Whether a file name is one Sinew writes aside (NAME.tmp next to NAME): the only .tmp files a new run
// removes.
bool own_temporary(const std::string& file, const std::string& scene) {
  // Every file Sinew writes aside before putting it in place (io_detail::write_durably and the HDF5
  // writers): step files, surfaces and skins, the skin caches and their rest shape, the logs.
  static const std::regex own(
      R"(((mesh(_layout\d+)?|checkpoint|step_\d{6})\.h5|(surface|skin|lbs)_\d{6}\.obj|skin_rest\.obj|skin\.(glb|pc2|frames)|(log|newton)\.csv)\.tmp)");
  return std::regex_match(file, own) || file == scene + ".xdmf.tmp";
}

// Creates an HDF5 file for collective parallel writing.
hid_t create_parallel(const std::string& path, MPI_Comm comm) {
  H5 fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "file access properties");
  H5Pset_fapl_mpio(fapl.id(), comm, MPI_INFO_NULL);
  return H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.id());
}

// Writes an HDF5 file aside with `fill` (collective), closes it checking the flush, and renames it into
// place on rank 0; any failure on any rank is an error on every rank and the old file stays.
template <class Fill>
void write_file(const std::string& path, MPI_Comm comm, bool root, Fill&& fill) {
  const std::string tmp = path + ".tmp";
  collectively(comm, [&] {
    H5 file(create_parallel(tmp, comm), H5Fclose, "creating " + tmp);
    fill(file.id(), tmp);
    file.close();
  });
  collectively(comm, [&] {
    if (root) replace_durably(tmp, path);
  });
}

// The energy terms' states in group "/term NAME": a shared array KEY as dataset "shared KEY" holding
// its length and then its values (never zero-length), a nodal array as "nodal KEY" with a row per node
// in output order (rows x components), like /displacement.
void write_term_states(hid_t file, const Output::TermStates& terms, const Mesh& m, const std::string& tmp, bool root) {
  const long long n_owned = static_cast<long long>(m.n_owned_nodes);
  for (const auto& [name, state] : terms) {
    const std::string group = "/term " + name;
    H5 g(H5Gcreate2(file, group.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, tmp + ": create " + group);
    for (const auto& [key, values] : state.shared) {
      std::vector<double> record{static_cast<double>(values.size())};
      record.insert(record.end(), values.begin(), values.end());
      const long long n = static_cast<long long>(record.size());
      write_rows(file, group + "/shared " + key, H5T_NATIVE_DOUBLE, n, 1, 0, root ? n : 0, record.data(), tmp);
    }
    for (const auto& nodal : state.nodal) {
      if (nodal.values.size() != static_cast<std::size_t>(n_owned * nodal.components))
        throw std::logic_error("write_checkpoint: term '" + name + "' array '" + nodal.name + "' is not one row per owned node");
      write_rows(file, group + "/nodal " + nodal.name, H5T_NATIVE_DOUBLE, m.global_nodes, nodal.components, m.first_output_node,
                 n_owned, nodal.values.data(), tmp);
    }
  }
}

}  // namespace

Output::Output(const OutputParameters& params, const System& system, const std::string& name, int steps,
               int restart_step)
    : params_(params), sys_(system), name_(name), steps_(steps), restart_step_(restart_step) {
  root_ = system.comm()->getRank() == 0;
  started_ = wall_clock();
  dir_ = params.directory.empty() ? "results/" + name_ : params.directory;
  try {
    collectively(raw_comm(*system.comm()), [&] {
      if (!root_) return;
      std::error_code ec;
      if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
        throw InputError("Output: results folder '" + dir_ + "' is a file, not a folder (name another 'Directory')",
                         InputErrorKind::File);
      fs::create_directories(dir_, ec);
      if (ec) throw InputError("Output: cannot create results folder '" + dir_ + "': " + ec.message(), InputErrorKind::File);
      // Files a crash left half-written: never read, so remove them (only those Sinew names itself: the
      // folder may be a user's, or /tmp).
      for (const auto& entry : fs::directory_iterator(dir_, ec))
        if (own_temporary(entry.path().filename().string(), name_)) fs::remove(entry.path(), ec);
      // On restart keep the rows of the steps up to the checkpoint (a row written after it belongs to
      // a step that will be computed again).
      // The run's columns, then each energy term's (System::log_columns: its energy share and its own).
      std::string header =
          "step,load,cuts,newton_iterations,cg_iterations,initial_residual,final_residual,energy,volume_ratio,"
          "min_J,inverted_points,seconds_assembly,seconds_preconditioner,seconds_linear,seconds_line_search,"
          "seconds_total,seconds_rounds,pattern_changes,time,kinetic_energy,first_guess";
      for (const std::string& c : system.log_columns()) header += "," + c;
      open_csv(log_, dir_ + "/log.csv", restart_step, header);
      open_csv(newton_log_, dir_ + "/newton.csv", restart_step,
               "step,load,iteration,residual,cg_iterations,step_length,exact_hessian,direction_max,step_bound");
    });
  } catch (const std::runtime_error& e) {
    if (dynamic_cast<const InputError*>(&e)) throw;
    throw InputError(e.what(), InputErrorKind::File);
  }
  if (!params_.hdf5) return;
  MPI_Comm comm = raw_comm(*system.comm());
  layout_ = layout_digest(system.mesh(), comm);
  if (restart_step < 0) return;  // a new run writes mesh.h5 (write_mesh)
  // A restart pairs every step file with the mesh file of its row order: the earlier run's steps with
  // the mesh file it wrote, the new steps with one of this run's layout. On another number of ranks (or
  // into a new folder) that is a new file, mesh_layoutK.h5 (or mesh.h5 where there is none), so that
  // ParaView never draws new rows on old connectivity.
  std::string mesh_name;
  collectively(comm, [&] {
    if (!root_) return;
    std::vector<std::pair<std::string, std::optional<std::uint64_t>>> meshes;  // on disk, with their layout
    if (fs::exists(dir_ + "/mesh.h5")) meshes.emplace_back("mesh.h5", read_layout(dir_ + "/mesh.h5"));
    for (int k = 1; fs::exists(dir_ + "/mesh_layout" + std::to_string(k) + ".h5"); ++k) {
      const std::string f = "mesh_layout" + std::to_string(k) + ".h5";
      meshes.emplace_back(f, read_layout(dir_ + "/" + f));
    }
    for (const auto& [f, layout] : meshes)
      if (layout == layout_) mesh_name = f;
    if (mesh_name.empty()) {
      mesh_on_disk_ = false;
      mesh_name = "mesh.h5";
      for (int k = 1; fs::exists(dir_ + "/" + mesh_name); ++k) mesh_name = "mesh_layout" + std::to_string(k) + ".h5";
    } else {
      mesh_on_disk_ = true;
    }
    // Step files already on disk up to the restart point belong to the run's history, each with the
    // mesh file of its layout (one written before layouts were recorded: mesh.h5, which it came with).
    for (int k = 0; k <= restart_step; ++k) {
      if (!fs::exists(step_file(k))) continue;
      const auto layout = read_layout(step_file(k));
      std::string mesh = layout ? "" : "mesh.h5";
      for (const auto& [f, l] : meshes)
        if (layout && l == layout) mesh = f;
      if (mesh.empty() || !fs::exists(dir_ + "/" + mesh)) continue;  // its mesh file is gone: not indexable
      written_.push_back({k, static_cast<double>(k) / steps_, mesh});
    }
  });
  // Rank 0 decided; the others need the file name and whether to write it.
  int on_disk = mesh_on_disk_ ? 1 : 0, len = static_cast<int>(mesh_name.size());
  MPI_Bcast(&on_disk, 1, MPI_INT, 0, comm);
  MPI_Bcast(&len, 1, MPI_INT, 0, comm);
  mesh_name.resize(len);
  MPI_Bcast(mesh_name.data(), len, MPI_CHAR, 0, comm);
  mesh_on_disk_ = on_disk != 0;
  mesh_name_ = mesh_name;
}

void Output::add_skin_frame(int step, double load, const std::vector<double>& x, const std::vector<double>& J,
                            const std::vector<std::vector<double>>& sequences) {
  const EmbeddedSurface& s = *sys_.mesh().embedded;
  const std::size_t V = s.rest.size();
  if (!skin_file_) {
    // Fields: det F at the skin, and the distance to each surface written beside it with the same
    // vertices (a rig's own linear-blend skin: where the simulation departs from it).
    skin_fields_ = {"J"};
    for (std::size_t k = 0; k < sequences_.size(); ++k)
      if (sequences[k].size() == 3 * V) skin_fields_.push_back(sequences_[k].first + "_distance");
    std::string note;
    skin_file_ = std::make_unique<SkinFrameFile>(dir_ + "/skin.frames", V, skin_fields_, restart_step_, skin_frames_, note);
    if (!note.empty()) std::printf("  output note: %s\n", note.c_str());
    // The rest skin the point cache applies to (and the glTF file's mesh).
    std::vector<double> rest;
    for (const auto& p : s.rest) rest.insert(rest.end(), p.begin(), p.end());
    if (params_.skin_pc2.value_or(true)) write_obj_file(dir_ + "/skin_rest.obj", rest, s.triangles, "rest skin of skin.pc2");
  }
  SkinFrame f;
  f.step = step;
  f.load = load;
  f.time = frame_time_ ? frame_time_(load) : load * steps_ / frame_rate_;
  // Animation times must increase strictly: a frame no later than the last one (the fields of a failed
  // step written at the last converged load) adds nothing to the caches.
  if (!skin_frames_.empty() && !(f.time > skin_frames_.back().time)) return;
  f.x.assign(x.begin(), x.end());
  f.fields.emplace_back(J.begin(), J.end());
  for (std::size_t k = 0; k < sequences_.size(); ++k) {
    if (sequences[k].size() != 3 * V) continue;
    std::vector<float> d(V);
    for (std::size_t v = 0; v < V; ++v) {
      const double a = x[3 * v] - sequences[k][3 * v], b = x[3 * v + 1] - sequences[k][3 * v + 1], c = x[3 * v + 2] - sequences[k][3 * v + 2];
      d[v] = static_cast<float>(std::sqrt(a * a + b * b + c * c));
    }
    f.fields.push_back(std::move(d));
  }
  const double t0 = wall_clock();
  skin_file_->append(f);
  append_seconds_ += wall_clock() - t0;
  skin_frames_.push_back(std::move(f));
  // The exports cost O(frames) each: refresh them while they stay under 2% of the run's time, and
  // always at the end (finish).
  if (export_seconds_ <= 0.02 * (wall_clock() - started_) || step == steps_) write_skin_caches();
}

void Output::write_skin_caches() {
  if (!root_ || !skin_file_ || skin_frames_exported_ == skin_frames_.size()) return;
  const double t0 = wall_clock();
  const EmbeddedSurface& s = *sys_.mesh().embedded;
  SkinTrack track;
  track.name = name_;
  for (const auto& p : s.rest) track.rest.insert(track.rest.end(), p.begin(), p.end());
  track.triangles = s.triangles;
  track.field_names = skin_fields_;
  track.frame_rate = frame_rate_;
  if (skin_rig_.pose) track.rig = &skin_rig_;
  // The frames lent to the track, not copied (they may be the largest thing rank 0 holds).
  track.frames.swap(skin_frames_);
  try {
    if (params_.skin_gltf.value_or(true)) write_glb(dir_ + "/skin.glb", track);
    if (params_.skin_pc2.value_or(true)) write_pc2(dir_ + "/skin.pc2", track);
  } catch (...) {
    track.frames.swap(skin_frames_);
    throw;
  }
  track.frames.swap(skin_frames_);
  skin_frames_exported_ = skin_frames_.size();
  export_seconds_ += wall_clock() - t0;
}

void Output::finish() {
  collectively(raw_comm(*sys_.comm()), [&] { write_skin_caches(); });
}

std::string Output::skin_cache_summary() const {
  if (!root_ || !skin_file_) return "";
  auto mb = [&](const char* f) {
    std::error_code ec;
    const auto n = fs::file_size(dir_ + "/" + f, ec);
    return ec ? 0.0 : static_cast<double>(n) / 1e6;
  };
  char buf[256];
  std::snprintf(buf, sizeof buf, "skin caches: %zu frames of %zu vertices; skin.glb %.1f MB, skin.pc2 %.1f MB, skin.frames %.1f MB; "
                "%.2f s writing them (%.1f%% of the run)",
                skin_frames_.size(), sys_.mesh().embedded->rest.size(), mb("skin.glb"), mb("skin.pc2"), mb("skin.frames"),
                export_seconds_ + append_seconds_, 100.0 * (export_seconds_ + append_seconds_) / std::max(1e-9, wall_clock() - started_));
  return buf;
}

std::string Output::step_file(int step) const {
  std::ostringstream os;
  os << dir_ << "/step_" << std::setw(6) << std::setfill('0') << step << ".h5";
  return os.str();
}

void Output::write_mesh() {
  if (!params_.hdf5 || mesh_on_disk_) return;
  const Mesh& m = sys_.mesh();
  const long long n_owned = static_cast<long long>(m.n_owned_nodes), e_owned = static_cast<long long>(m.n_owned_elements);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
  auto C = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.conn);
  std::vector<double> xyz(3 * n_owned);
  for (long long n = 0; n < n_owned; ++n)
    for (int d = 0; d < 3; ++d) xyz[3 * n + d] = X(n, d);
  const int npe = nodes_per_element(m.type);
  std::vector<long long> conn(npe * e_owned);
  for (long long e = 0; e < e_owned; ++e)
    for (int a = 0; a < npe; ++a) conn[npe * e + a] = m.node_output_id[C(e, a)];
  // Rows are in output order (rank by rank); the global ids (lattice position or file order, the same
  // on any number of ranks) and a file's own tags stand beside them.
  const std::vector<long long> node_gid(m.node_gid.begin(), m.node_gid.begin() + n_owned);
  const std::vector<long long> element_gid(m.element_gid.begin(), m.element_gid.begin() + e_owned);
  write_file(dir_ + "/" + mesh_name_, raw_comm(*sys_.comm()), root_, [&](hid_t file, const std::string& tmp) {
    write_layout_attribute(file, "layout", layout_);
    write_rows(file, "/coordinates", H5T_NATIVE_DOUBLE, m.global_nodes, 3, m.first_output_node, n_owned, xyz.data(), tmp);
    write_rows(file, "/connectivity", H5T_NATIVE_LLONG, m.global_elements, npe, m.first_output_element, e_owned, conn.data(), tmp);
    write_rows(file, "/node_gid", H5T_NATIVE_LLONG, m.global_nodes, 1, m.first_output_node, n_owned, node_gid.data(), tmp);
    write_rows(file, "/element_gid", H5T_NATIVE_LLONG, m.global_elements, 1, m.first_output_element, e_owned, element_gid.data(), tmp);
    if (!m.node_tag.empty()) {
      write_rows(file, "/node_tag", H5T_NATIVE_LLONG, m.global_nodes, 1, m.first_output_node, n_owned, m.node_tag.data(), tmp);
      write_rows(file, "/element_tag", H5T_NATIVE_LLONG, m.global_elements, 1, m.first_output_element, e_owned,
                 m.element_tag.data(), tmp);
    }
  });
  mesh_on_disk_ = true;
}

std::string Output::surface_file(int step) const {
  std::ostringstream os;
  os << dir_ << "/surface_" << std::setw(6) << std::setfill('0') << step << ".obj";
  return os.str();
}

bool Output::skin_caches() const {
  return sys_.mesh().has_embedded && (params_.skin_gltf.value_or(true) || params_.skin_pc2.value_or(true));
}

void Output::set_frame_clock(std::function<double(double load)> time, double frame_rate) {
  frame_time_ = std::move(time);
  frame_rate_ = frame_rate;
}

void Output::write_step(int step, double load, const Vector& u, const NodeFields& node_fields,
                        const std::vector<TermState::Nodal>& element_fields) {
  const bool caches = skin_caches();
  if ((params_.surface || caches) && (step % (params_.every * params_.surface_every) == 0 || step == steps_)) {
    std::ostringstream what;
    what << "step " << step << ", load " << load;
    if (params_.surface) {
      if (!surface_) surface_ = std::make_unique<BoundarySurface>(sys_.mesh(), *sys_.comm());
      surface_->write_obj(surface_file(step), u, what.str());
    }
    // A voxelized body: its own skin, carried by the lattice (rank 0 holds it).
    std::vector<double> skin, J;
    if (sys_.mesh().has_embedded) {
      if (!skin_) skin_ = std::make_unique<EmbeddedSkin>(sys_.mesh(), u.getMap());
      skin_->deformed(u, skin, caches ? &J : nullptr);
    }
    std::vector<std::vector<double>> sequence_x(sequences_.size());
    collectively(raw_comm(*sys_.comm()), [&] {
      if (!root_) return;
      std::ostringstream path;
      path << dir_ << "/skin_" << std::setw(6) << std::setfill('0') << step << ".obj";
      if (params_.surface && sys_.mesh().has_embedded) write_obj_file(path.str(), skin, sys_.mesh().embedded->triangles, what.str());
      for (std::size_t k = 0; k < sequences_.size(); ++k) {
        const auto& [prefix, at] = sequences_[k];
        std::vector<std::array<int, 3>> triangles;
        at(load, sequence_x[k], triangles);
        if (!params_.surface) continue;
        std::ostringstream seq;
        seq << dir_ << "/" << prefix << "_" << std::setw(6) << std::setfill('0') << step << ".obj";
        write_obj_file(seq.str(), sequence_x[k], triangles, what.str());
      }
      if (caches) add_skin_frame(step, load, skin, J, sequence_x);
    });
  }
  if (!params_.hdf5) return;
  const Mesh& m = sys_.mesh();
  MPI_Comm comm = raw_comm(*sys_.comm());
  std::vector<double> psi, J;
  sys_.element_fields(u, psi, J);
  const long long n_owned = static_cast<long long>(m.n_owned_nodes), e_owned = static_cast<long long>(m.n_owned_elements);
  const long long first_node = m.first_output_node, first_el = m.first_output_element;
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
  auto uv = u.getLocalViewHost(Tpetra::Access::ReadOnly);
  std::vector<double> disp(3 * n_owned), pos(3 * n_owned);
  for (long long n = 0; n < n_owned; ++n)
    for (int d = 0; d < 3; ++d) {
      disp[3 * n + d] = uv(3 * n + d, 0);
      pos[3 * n + d] = X(n, d) + uv(3 * n + d, 0);
    }
  write_file(step_file(step), comm, root_, [&](hid_t file, const std::string& tmp) {
    write_rows(file, "/displacement", H5T_NATIVE_DOUBLE, m.global_nodes, 3, first_node, n_owned, disp.data(), tmp);
    write_rows(file, "/position", H5T_NATIVE_DOUBLE, m.global_nodes, 3, first_node, n_owned, pos.data(), tmp);
    write_rows(file, "/J", H5T_NATIVE_DOUBLE, m.global_elements, 1, first_el, e_owned, J.data(), tmp);
    write_rows(file, "/energy_density", H5T_NATIVE_DOUBLE, m.global_elements, 1, first_el, e_owned, psi.data(), tmp);
    for (const auto& [name, values] : node_fields) {
      const int cols = values.size() == static_cast<std::size_t>(3 * n_owned) && n_owned > 0 ? 3 : 1;
      write_rows(file, "/" + name, H5T_NATIVE_DOUBLE, m.global_nodes, cols, first_node, n_owned, values.data(), tmp);
    }
    for (const auto& f : element_fields)
      write_rows(file, "/" + f.name, H5T_NATIVE_DOUBLE, m.global_elements, f.components, first_el, e_owned, f.values.data(), tmp);
    write_attribute(file, "load", load);
    write_attribute(file, "step", step);
    write_layout_attribute(file, "layout", layout_);
  });
  node_fields_.clear();
  for (const auto& f : node_fields) {
    // Every rank agrees on a field's shape (a rank with no owned node cannot tell from its sizes).
    int vector = f.second.size() == 3 * m.n_owned_nodes && m.n_owned_nodes > 0 ? 1 : 0, any = 0;
    MPI_Allreduce(&vector, &any, 1, MPI_INT, MPI_MAX, comm);
    node_fields_.emplace_back(f.first, any ? 3 : 1);
  }
  element_fields_.clear();
  for (const auto& f : element_fields) element_fields_.emplace_back(f.name, f.components);
  written_.erase(std::remove_if(written_.begin(), written_.end(), [&](const Written& w) { return w.step == step; }),
                 written_.end());
  written_.push_back({step, load, mesh_name_});
  collectively(comm, [&] {
    if (root_) write_xdmf();
  });
}

void Output::write_xdmf() const {
  const Mesh& m = sys_.mesh();
  const int npe = nodes_per_element(m.type);
  const std::string topo = m.type == ElementType::Hex8 ? "Hexahedron" : "Tetrahedron";
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"" << name_ << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& [step, load, mesh] : written_) {
    const std::string f = fs::path(step_file(step)).filename().string();
    x << "   <Grid Name=\"step " << step << "\" GridType=\"Uniform\">\n"
      << "    <Time Value=\"" << load << "\"/>\n"
      << "    <Topology TopologyType=\"" << topo << "\" NumberOfElements=\"" << m.global_elements << "\">\n"
      << "     <DataItem Dimensions=\"" << m.global_elements << " " << npe
      << "\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">" << mesh << ":/connectivity</DataItem>\n"
      << "    </Topology>\n"
      << "    <Geometry GeometryType=\"XYZ\">\n"
      << "     <DataItem Dimensions=\"" << m.global_nodes << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << f
      << ":/position</DataItem>\n"
      << "    </Geometry>\n";
    auto attr = [&](const char* name, const char* type, const char* center, long long rows, int cols, const char* ds) {
      x << "    <Attribute Name=\"" << name << "\" AttributeType=\"" << type << "\" Center=\"" << center << "\">\n"
        << "     <DataItem Dimensions=\"" << rows << (cols > 1 ? " " + std::to_string(cols) : "")
        << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << f << ":" << ds << "</DataItem>\n"
        << "    </Attribute>\n";
    };
    attr("displacement", "Vector", "Node", m.global_nodes, 3, "/displacement");
    attr("J", "Scalar", "Cell", m.global_elements, 1, "/J");
    attr("energy_density", "Scalar", "Cell", m.global_elements, 1, "/energy_density");
    for (const auto& [name, cols] : node_fields_)
      attr(name.c_str(), cols == 3 ? "Vector" : "Scalar", "Node", m.global_nodes, cols, ("/" + name).c_str());
    for (const auto& [name, cols] : element_fields_)
      attr(name.c_str(), cols == 3 ? "Vector" : "Scalar", "Cell", m.global_elements, cols, ("/" + name).c_str());
    x << "   </Grid>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  const std::string path = dir_ + "/" + name_ + ".xdmf", tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << x.str();
    out.close();
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  replace_durably(tmp, path);
}

void Output::log_newton(int step, double load, const NewtonIterate& it) {
  if (!root_) return;
  newton_log_ << std::setprecision(10) << step << "," << load << "," << it.iteration << "," << it.residual << ","
              << it.linear_iterations << "," << it.step << "," << (it.exact_terms ? 2 : it.exact_hessian ? 1 : 0) << "," << it.direction_max
              << "," << it.step_bound << "\n";
  newton_log_.flush();
}

void Output::log(const StepRecord& r) {
  // Collective: a row that cannot be written (disk full) stops every rank with a message.
  collectively(raw_comm(*sys_.comm()), [&] {
    if (!root_) return;
    write_log_row(r);
    log_.flush();
    newton_log_.flush();
    if (!log_ || !newton_log_) throw InputError("Output: writing " + dir_ + "/log.csv or newton.csv failed (disk full?)",
                                                InputErrorKind::File);
  });
}

void Output::write_log_row(const StepRecord& r) {
  const auto& s = r.solve;
  log_ << std::setprecision(10) << r.step << "," << r.load << "," << r.cuts << "," << s.newton_iterations << ","
       << s.linear_iterations << "," << s.initial_residual << "," << s.final_residual << "," << r.totals.energy << ","
       << r.volume_ratio << "," << r.totals.min_J << "," << r.totals.inverted << "," << s.seconds_assembly << ","
       << s.seconds_preconditioner << "," << s.seconds_linear << "," << s.seconds_line_search << "," << s.seconds_total
       << "," << r.seconds_rounds << "," << r.pattern_changes << "," << r.time << "," << r.kinetic << "," << r.first_guess;
  for (double v : r.term_values) log_ << "," << v;
  log_ << "\n";
  log_.flush();
}

void Output::write_checkpoint(const LoadState& at, const Vector& u, const Vector* previous, const Vector* velocity,
                              const TermStates& terms) {
  const Mesh& m = sys_.mesh();
  const long long n_owned = static_cast<long long>(m.n_owned_nodes);
  auto rows_of = [&](const Vector& v) {
    auto vv = v.getLocalViewHost(Tpetra::Access::ReadOnly);
    return std::vector<double>(vv.data(), vv.data() + 3 * n_owned);
  };
  const std::vector<double> disp = rows_of(u);
  const bool with_previous = previous && at.previous_load >= 0.0;
  const std::vector<double> prev = with_previous ? rows_of(*previous) : std::vector<double>();
  const std::vector<double> vel = velocity ? rows_of(*velocity) : std::vector<double>();
  const std::vector<long long> gid(m.node_gid.begin(), m.node_gid.begin() + n_owned);
  // The rename is atomic: a kill at any point leaves either the old checkpoint or the new one. Rows are
  // in output order with each node's global id beside them, so any number of ranks can read it.
  write_file(checkpoint_file(), raw_comm(*sys_.comm()), root_, [&](hid_t file, const std::string& tmp) {
    write_rows(file, "/displacement", H5T_NATIVE_DOUBLE, m.global_nodes, 3, m.first_output_node, n_owned, disp.data(), tmp);
    write_rows(file, "/node_gid", H5T_NATIVE_LLONG, m.global_nodes, 1, m.first_output_node, n_owned, gid.data(), tmp);
    write_attribute(file, "step", at.step);
    write_attribute(file, "load", at.load);
    write_attribute(file, "increment", at.increment);
    write_attribute(file, "cuts", at.cuts);
    // The converged state before this one, which the extrapolating predictor needs for the next step.
    if (with_previous) {
      write_rows(file, "/previous_displacement", H5T_NATIVE_DOUBLE, m.global_nodes, 3, m.first_output_node, n_owned,
                 prev.data(), tmp);
      write_attribute(file, "previous_load", at.previous_load);
    }
    if (velocity)
      write_rows(file, "/velocity", H5T_NATIVE_DOUBLE, m.global_nodes, 3, m.first_output_node, n_owned, vel.data(), tmp);
    write_attribute(file, "global_nodes", static_cast<double>(m.global_nodes));
    write_attribute(file, "steps", steps_);
    write_term_states(file, terms, m, tmp, root_);
    // Each physics section's digest, and its entries, so that a restart can name what differs and accept
    // parameters added since at their defaults (a char dataset: an attribute holds at most 64 kB).
    for (const auto& section : physics_) {
      write_attribute(file, ("physics " + section.name).c_str(), section.fingerprint.digest);
      const std::string text = encode_entries(section.fingerprint.entries);
      const long long n = static_cast<long long>(text.size());
      if (n > 0) write_rows(file, "/physics " + section.name, H5T_NATIVE_CHAR, n, 1, 0, root_ ? n : 0, text.data(), tmp);
    }
  });
}

namespace {

// A checkpoint file opened by one rank (no collective open), with its scalar attributes checked.
class CheckpointFile {
 public:
  CheckpointFile(const std::string& path, std::function<void(const std::string&)> fail) : path_(path), fail_(std::move(fail)) {
    std::error_code ec;
    if (!fs::exists(path, ec)) fail_("does not exist");
    if (!fs::is_regular_file(path, ec)) fail_("is not a regular file");
    if (H5Fis_hdf5(path.c_str()) <= 0) fail_("is not an HDF5 file");
    H5 fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "file access properties");
    const hid_t fid = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.id());
    if (fid < 0) fail_("is not a readable HDF5 file");
    file_ = std::make_unique<H5>(fid, H5Fclose, "open " + path);
  }
  hid_t id() const { return file_->id(); }
  bool has_attribute(const char* name) const { return H5Aexists(id(), name) > 0; }
  bool has(const char* dataset) const { return H5Lexists(id(), dataset, H5P_DEFAULT) > 0; }
  // A scalar attribute within [lo, hi].
  double attribute(const char* name, double lo, double hi) const {
    if (!has_attribute(name)) fail_(std::string("has no '") + name + "' attribute (not a Sinew checkpoint?)");
    H5 a(H5Aopen(id(), name, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
    H5 space(H5Aget_space(a.id()), H5Sclose, "attribute space");
    if (H5Sget_simple_extent_npoints(space.id()) != 1) fail_(std::string("attribute '") + name + "' is not a scalar");
    double v = NAN;
    if (H5Aread(a.id(), H5T_NATIVE_DOUBLE, &v) < 0) fail_(std::string("cannot read attribute '") + name + "'");
    if (!std::isfinite(v) || v < lo || v > hi)
      fail_(std::string("attribute '") + name + "' = " + std::to_string(v) + " is out of range (corrupt file?)");
    return v;
  }
  // Rows [first, first + count) of a rows x cols dataset.
  void read_rows(const char* name, hid_t type, long long first, long long count, int cols, void* out) const {
    H5 d(H5Dopen2(id(), name, H5P_DEFAULT), H5Dclose, path_ + ": " + name);
    H5 sp(H5Dget_space(d.id()), H5Sclose, "dataspace");
    hsize_t start[2] = {static_cast<hsize_t>(first), 0}, cnt[2] = {static_cast<hsize_t>(count), static_cast<hsize_t>(cols)};
    H5 mem(H5Screate_simple(cols == 1 ? 1 : 2, cnt, nullptr), H5Sclose, "memspace");
    if (count > 0) {
      H5Sselect_hyperslab(sp.id(), H5S_SELECT_SET, start, nullptr, cnt, nullptr);
    } else {
      H5Sselect_none(sp.id());
      H5Sselect_none(mem.id());
    }
    if (H5Dread(d.id(), type, mem.id(), sp.id(), H5P_DEFAULT, out) < 0) fail_(std::string("cannot read ") + name);
  }
  // The rank of a dataset and its extents (dims[1] = 1 for one dimension).
  int extent(const std::string& name, hsize_t dims[2]) const {
    H5 d(H5Dopen2(id(), name.c_str(), H5P_DEFAULT), H5Dclose, path_ + ": " + name);
    H5 sp(H5Dget_space(d.id()), H5Sclose, "dataspace");
    dims[1] = 1;
    return H5Sget_simple_extent_dims(sp.id(), dims, nullptr);
  }
  void fail(const std::string& why) const { fail_(why); }

 private:
  std::string path_;
  std::function<void(const std::string&)> fail_;
  std::unique_ptr<H5> file_;
};

// The same physics: a checkpoint of another material, load or mesh would continue a different problem
// from a state that is not its own (checkpoints written before digests were kept pass). Returns the
// notes on entries new since the checkpoint (taken at their defaults); fails naming what differs.
std::vector<std::string> check_physics(const CheckpointFile& file, const Output::Physics& physics) {
  std::vector<std::string> notes, changed, details;
  for (const auto& section : physics) {
    const std::string name = "physics " + section.name;
    if (!file.has_attribute(name.c_str())) continue;
    H5 a(H5Aopen(file.id(), name.c_str(), H5P_DEFAULT), H5Aclose, "attribute " + name);
    H5 type(H5Aget_type(a.id()), H5Tclose, "attribute type");
    std::string stored(H5Tget_size(type.id()), '\0');
    if (H5Tget_class(type.id()) != H5T_STRING || H5Aread(a.id(), type.id(), stored.data()) < 0)
      file.fail("cannot read attribute '" + name + "' (corrupt file?)");
    stored.erase(std::find(stored.begin(), stored.end(), '\0'), stored.end());
    if (stored == section.fingerprint.digest) continue;
    // Checkpoints written before the entries were kept have the digest only.
    const std::string dataset = "/" + name;
    if (!file.has(dataset.c_str())) {
      changed.push_back("'" + section.name + "'");
      continue;
    }
    std::vector<SectionEntry> entries;
    try {
      entries = decode_entries(read_text(file.id(), dataset));
    } catch (const std::exception& e) {
      file.fail("cannot read '" + dataset + "' (corrupt file?): " + e.what());
    }
    const EntryDifference d = compare_entries(entries, section.fingerprint.entries, section.name + "/");
    for (const auto& e : d.new_at_default) notes.push_back(e + " is new since the checkpoint was written; taken at its default");
    if (d.differ.empty()) continue;
    changed.push_back("'" + section.name + "'");
    details.insert(details.end(), d.differ.begin(), d.differ.end());
  }
  if (!changed.empty()) {
    std::string listed;
    const std::size_t shown = std::min<std::size_t>(details.size(), 8);
    for (std::size_t k = 0; k < shown; ++k) listed += (k ? "; " : " (") + details[k];
    if (details.size() > shown) listed += "; and " + std::to_string(details.size() - shown) + " more";
    if (shown) listed += ")";
    file.fail("was written by a run whose " + or_list(changed) + " section" + (changed.size() > 1 ? "s differ" : " differs") +
              " from this scene's" + listed + "; a restart continues the same physics (sinew --restart-anyway FILE "
              "continues it with this scene's)");
  }
  return notes;
}

// Where the load path stood: step, load, the cut increment and its cuts, the previous load.
void read_load_state(const CheckpointFile& file, int steps, bool want_previous, LoadState& c) {
  const double step = file.attribute("step", 0, steps);
  c.step = static_cast<int>(step);
  if (c.step != step) file.fail("attribute 'step' is not a whole number (corrupt file?)");
  c.load = file.attribute("load", 0.0, 1.0);
  // Checkpoints written before cut steps were recorded lack these: they were taken at step ends.
  c.increment = file.has_attribute("increment") ? file.attribute("increment", 0.0, 1.0) : 0.0;
  c.cuts = file.has_attribute("cuts") ? static_cast<int>(file.attribute("cuts", 0, 64)) : 0;
  if (c.load < static_cast<double>(c.step) / steps - 1e-12 || c.load > static_cast<double>(c.step + 1) / steps + 1e-12)
    file.fail("load " + std::to_string(c.load) + " does not lie within step " + std::to_string(c.step + 1) + " (corrupt file?)");
  // Written by runs with the extrapolating predictor; without it the next step starts unextrapolated.
  if (want_previous && file.has_attribute("previous_load")) c.previous_load = file.attribute("previous_load", 0.0, c.load);
}

// A nodes x 3 field of the checkpoint: this rank's block of rows, then its owners' copy.
struct NodeField {
  const char* name;
  Vector* out;
  std::vector<double> values;
};

void read_node_field(const CheckpointFile& file, long long global_nodes, long long r0, long long rows, NodeField& f) {
  if (!file.has(f.name)) file.fail(std::string("has no ") + f.name + " dataset");
  hsize_t dims[2] = {0, 0};
  if (file.extent(f.name, dims) != 2 || dims[0] != static_cast<hsize_t>(global_nodes) || dims[1] != 3)
    file.fail(std::string(f.name) + " does not have the shape nodes x 3 of this mesh");
  f.values.resize(3 * rows);
  file.read_rows(f.name, H5T_NATIVE_DOUBLE, r0, rows, 3, f.values.data());
  for (long long i = 0; i < 3 * rows; ++i)
    if (!std::isfinite(f.values[i]))
      file.fail(std::string(f.name) + " row " + std::to_string(r0 + i / 3) + " holds a non-finite value (corrupt file?)");
}

// The energy terms' states in a checkpoint (write_term_states), read in the two phases of
// read_checkpoint: each rank reads the shared arrays and its block of nodal rows from the file it has
// open, then the nodal rows go to the ranks owning their nodes (a Tpetra import by node id).
struct TermBlocks {
  struct Block {
    std::string term, key;
    int components;
    std::vector<double> values;  // this rank's block of rows
  };
  Output::TermStates states;
  std::vector<Block> blocks;
};

void read_term_blocks(const CheckpointFile& file, const System& sys, long long r0, long long rows, TermBlocks& out) {
  for (const auto& term : sys.terms()) {
    const std::string group = std::string("/term ") + term->name();
    if (!file.has(group.c_str())) continue;
    H5 g(H5Gopen2(file.id(), group.c_str(), H5P_DEFAULT), H5Gclose, group);
    H5G_info_t info;
    if (H5Gget_info(g.id(), &info) < 0) file.fail("cannot list " + group);
    TermState state;
    for (hsize_t k = 0; k < info.nlinks; ++k) {
      char buf[256] = {0};
      if (H5Lget_name_by_idx(g.id(), ".", H5_INDEX_NAME, H5_ITER_INC, k, buf, sizeof buf, H5P_DEFAULT) < 0)
        file.fail("cannot list " + group);
      const std::string item = buf, dataset = group + "/" + item;
      hsize_t dims[2] = {0, 1};
      const int ndims = file.extent(dataset, dims);
      if (item.rfind("shared ", 0) == 0) {
        if (ndims != 1 || dims[0] < 1) file.fail(dataset + " is not a record (corrupt file?)");
        std::vector<double> record(dims[0]);
        file.read_rows(dataset.c_str(), H5T_NATIVE_DOUBLE, 0, static_cast<long long>(dims[0]), 1, record.data());
        if (record[0] != static_cast<double>(dims[0] - 1)) file.fail(dataset + " does not hold its length (corrupt file?)");
        state.shared.emplace_back(item.substr(7), std::vector<double>(record.begin() + 1, record.end()));
      } else if (item.rfind("nodal ", 0) == 0) {
        if (dims[0] != static_cast<hsize_t>(sys.mesh().global_nodes)) file.fail(dataset + " does not have a row per node of this mesh");
        TermBlocks::Block b{term->name(), item.substr(6), static_cast<int>(dims[1]), std::vector<double>(rows * dims[1])};
        file.read_rows(dataset.c_str(), H5T_NATIVE_DOUBLE, r0, rows, b.components, b.values.data());
        out.blocks.push_back(std::move(b));
      }
    }
    out.states.emplace_back(term->name(), std::move(state));
  }
}

// Collective: the nodal blocks (rows of node ids `gid`) to the owned nodes, into their terms' states.
Output::TermStates import_term_blocks(TermBlocks in, const std::vector<long long>& gid, const System& sys) {
  if (in.blocks.empty()) return std::move(in.states);
  const std::size_t rows = gid.size(), n_owned = sys.mesh().n_owned_nodes;
  const std::vector<GO> gids(gid.begin(), gid.end());
  const auto block_map = Teuchos::rcp(new Map(Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid(),
                                              Teuchos::ArrayView<const GO>(gids), 0, sys.comm()));
  const Import import(block_map, sys.owned_nodes());
  for (TermBlocks::Block& b : in.blocks) {
    MultiVector from(block_map, b.components), to(sys.owned_nodes(), b.components);
    {
      auto v = from.getLocalViewHost(Tpetra::Access::OverwriteAll);
      for (std::size_t r = 0; r < rows; ++r)
        for (int c = 0; c < b.components; ++c) v(r, c) = b.values[r * b.components + c];
    }
    to.doImport(from, import, Tpetra::INSERT);
    TermState::Nodal nodal{b.key, b.components, std::vector<double>(n_owned * b.components)};
    auto v = to.getLocalViewHost(Tpetra::Access::ReadOnly);
    for (std::size_t n = 0; n < n_owned; ++n)
      for (int c = 0; c < b.components; ++c) nodal.values[n * b.components + c] = v(n, c);
    for (auto& [name, state] : in.states)
      if (name == b.term) state.nodal.push_back(std::move(nodal));
  }
  return std::move(in.states);
}

}  // namespace

LoadState Output::read_checkpoint(const std::string& path, const System& sys, int steps, Vector& u,
                                  Vector* previous, Vector* velocity, const Physics* physics, TermStates* terms) {
  const Mesh& m = sys.mesh();
  MPI_Comm comm = raw_comm(*sys.comm());
  LoadState c;
  const std::string where = "restart file '" + path + "'";
  auto fail = [&](const std::string& why) { throw InputError(where + ": " + why, InputErrorKind::File); };
  // Three phases, so that no rank throws while another waits in a collective call: (1) every rank reads
  // and checks its own block of rows (collectively: a bad row on one rank is an error on all); (2) the
  // blocks go to the ranks owning their nodes (Tpetra import: collective, throws nothing); (3) every
  // rank checks that its nodes were all covered (collectively again).
  int rank = 0, P = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &P);
  const long long N = m.global_nodes;
  const long long r0 = N * rank / P, rows = N * (rank + 1) / P - r0;
  std::vector<long long> gid(rows);
  std::vector<NodeField> fields{{"/displacement", &u, {}}};
  TermBlocks term_blocks;
  collectively(comm, [&] {
    QuietHdf5 quiet;
    const CheckpointFile file(path, fail);
    const long long nodes = static_cast<long long>(file.attribute("global_nodes", 0, 1e15));
    if (nodes != m.global_nodes)
      fail("was written for a mesh of " + std::to_string(nodes) + " nodes; this scene has " + std::to_string(m.global_nodes));
    const int file_steps = static_cast<int>(file.attribute("steps", 1, 1e9));
    if (file_steps != steps)
      fail("was written for " + std::to_string(file_steps) + " load steps; this scene has " + std::to_string(steps));
    if (physics) c.notes = check_physics(file, *physics);
    read_load_state(file, steps, previous != nullptr, c);
    if (previous && c.previous_load >= 0.0) fields.push_back({"/previous_displacement", previous, {}});
    if (velocity) {
      if (!file.has("/velocity")) fail("has no /velocity: it was written by a quasi-static run, and this scene is dynamic");
      fields.push_back({"/velocity", velocity, {}});
    }
    // Each rank reads a block of rows, whatever the layout that wrote them.
    if (file.has("/node_gid")) {
      file.read_rows("/node_gid", H5T_NATIVE_LLONG, r0, rows, 1, gid.data());
      for (long long k = 0; k < rows; ++k)
        if (gid[k] < 0 || gid[k] >= N)
          fail("/node_gid row " + std::to_string(r0 + k) + " holds " + std::to_string(gid[k]) + ", not a node of this mesh (corrupt file?)");
    } else {
      for (long long k = 0; k < rows; ++k) gid[k] = r0 + k;  // written before /node_gid existed: rows were ids
    }
    for (NodeField& f : fields) read_node_field(file, N, r0, rows, f);
    if (terms) read_term_blocks(file, sys, r0, rows, term_blocks);
  });
  // The rows go to the ranks owning their nodes (a Tpetra import by global id).
  std::vector<GO> dofs(3 * rows);
  for (long long k = 0; k < rows; ++k)
    for (int d = 0; d < 3; ++d) dofs[3 * k + d] = 3 * gid[k] + d;
  const auto block_map = Teuchos::rcp(new Map(Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid(),
                                              Teuchos::ArrayView<const GO>(dofs), 0, sys.comm()));
  const Import import(block_map, u.getMap());
  for (NodeField& f : fields) {
    Vector block(block_map);
    {
      auto bv = block.getLocalViewHost(Tpetra::Access::OverwriteAll);
      for (long long i = 0; i < 3 * rows; ++i) bv(i, 0) = f.values[i];
    }
    f.out->putScalar(NAN);
    f.out->doImport(block, import, Tpetra::INSERT);
  }
  collectively(comm, [&] {
    for (const NodeField& f : fields) {
      auto ov = f.out->getLocalViewHost(Tpetra::Access::ReadOnly);
      for (std::size_t i = 0; i < ov.extent(0); ++i)
        if (!std::isfinite(ov(i, 0)))
          fail(std::string(f.name) + " does not cover node " + std::to_string(m.node_gid[i / 3]) + " (corrupt file?)");
    }
  });
  if (terms) *terms = import_term_blocks(std::move(term_blocks), gid, sys);
  return c;
}

}  // namespace sinew
