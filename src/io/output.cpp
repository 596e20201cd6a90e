#include <sinew/core/errors.hpp>
#include <sinew/core/validation.hpp>
#include <sinew/io/output.hpp>

#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_Vector.hpp>
#include <hdf5.h>

#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace sinew {

namespace fs = std::filesystem;

Teuchos::ParameterList valid_output_parameters() {
  Teuchos::ParameterList v("Output");
  v.set("Directory", std::string(""), "results folder (default results/<Scene>)");
  v.set("Every", 1, "write fields every this many steps (the last step is always written)");
  v.set("HDF5", true, "write HDF5/XDMF fields (the CSV log is always written)");
  v.set("Checkpoint every", 1, "write DIR/checkpoint.h5 every this many steps (0: never); sinew --restart continues from it");
  return v;
}

namespace {

MPI_Comm raw_comm(const Teuchos::Comm<int>& comm) {
  if (auto mpi = dynamic_cast<const Teuchos::MpiComm<int>*>(&comm)) return *mpi->getRawMpiComm();
  return MPI_COMM_SELF;
}

// Thin RAII for HDF5 handles; every failure becomes an exception naming the file.
struct H5 {
  hid_t id;
  herr_t (*close)(hid_t);
  H5(hid_t i, herr_t (*c)(hid_t), const std::string& what) : id(i), close(c) {
    if (id < 0) throw std::runtime_error("HDF5: " + what + " failed");
  }
  ~H5() {
    if (id >= 0) close(id);
  }
  H5(const H5&) = delete;
  H5& operator=(const H5&) = delete;
};

// Collective write of rows [first, first + count) of a rows x cols dataset.
template <class T>
void write_rows(hid_t file, const std::string& name, hid_t type, long long rows, int cols, long long first,
                long long count, const T* data, const std::string& fname) {
  hsize_t dims[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(cols)};
  const int rank = cols == 1 ? 1 : 2;
  H5 space(H5Screate_simple(rank, dims, nullptr), H5Sclose, fname + ": dataspace " + name);
  H5 dset(H5Dcreate2(file, name.c_str(), type, space.id, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
          fname + ": create " + name);
  hsize_t start[2] = {static_cast<hsize_t>(first), 0}, cnt[2] = {static_cast<hsize_t>(count), static_cast<hsize_t>(cols)};
  H5 mem(H5Screate_simple(rank, cnt, nullptr), H5Sclose, fname + ": memspace " + name);
  if (count > 0)
    H5Sselect_hyperslab(space.id, H5S_SELECT_SET, start, nullptr, cnt, nullptr);
  else {
    H5Sselect_none(space.id);
    H5Sselect_none(mem.id);
  }
  H5 dxpl(H5Pcreate(H5P_DATASET_XFER), H5Pclose, "transfer properties");
  H5Pset_dxpl_mpio(dxpl.id, H5FD_MPIO_COLLECTIVE);
  if (H5Dwrite(dset.id, type, mem.id, space.id, dxpl.id, data) < 0)
    throw std::runtime_error("HDF5: writing " + name + " to " + fname + " failed");
}

void write_attribute(hid_t file, const char* name, double value) {
  H5 space(H5Screate(H5S_SCALAR), H5Sclose, "attribute space");
  H5 attr(H5Acreate2(file, name, H5T_NATIVE_DOUBLE, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, "attribute");
  H5Awrite(attr.id, H5T_NATIVE_DOUBLE, &value);
}

// Opens (creates) an HDF5 file for collective parallel writing.
hid_t create_parallel(const std::string& path, MPI_Comm comm) {
  H5 fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "file access properties");
  H5Pset_fapl_mpio(fapl.id, comm, MPI_INFO_NULL);
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.id);
  if (f < 0) throw std::runtime_error("HDF5: cannot create " + path);
  return f;
}

}  // namespace

Output::Output(const Teuchos::ParameterList& params, const Scene& scene, const std::string& scene_file, int restart_step)
    : scene_(scene), name_(scene.name()) {
  const auto& comm = *scene.system().comm();
  root_ = comm.getRank() == 0;
  try {
    require_known_entries(params, valid_output_parameters(), "Output");
  } catch (const InputError& e) {
    throw e.prefixed(scene_file + ": ");
  }
  dir_ = get_or<std::string>(params, "Directory", "");
  if (dir_.empty()) dir_ = "results/" + name_;
  every_ = get_or<int>(params, "Every", 1);
  if (every_ < 1) throw InputError(scene_file + ": Output: 'Every' must be at least 1");
  hdf5_ = get_or<bool>(params, "HDF5", true);
  checkpoint_every_ = get_or<int>(params, "Checkpoint every", 1);
  if (checkpoint_every_ < 0) throw InputError(scene_file + ": Output: 'Checkpoint every' must be >= 0");
  int ok = 1;
  std::string err;
  if (root_) {
    std::error_code ec;
    fs::create_directories(dir_, ec);
    if (ec) {
      ok = 0;
      err = ec.message();
    } else {
      // On restart keep the rows of the steps before the checkpoint (a row written after it belongs to
      // a step that will be computed again).
      std::vector<std::string> keep;
      if (restart_step >= 0) {
        std::ifstream old(dir_ + "/log.csv");
        std::string line;
        if (std::getline(old, line))
          while (std::getline(old, line))
            if (!line.empty() && std::atoi(line.c_str()) <= restart_step) keep.push_back(line);
      }
      log_.open(dir_ + "/log.csv", std::ios::trunc);
      if (!log_) {
        ok = 0;
        err = "cannot write " + dir_ + "/log.csv";
      } else {
        log_ << "step,load,cuts,newton_iterations,cg_iterations,initial_residual,final_residual,energy,volume_ratio,"
                "min_J,inverted_points,seconds_assembly,seconds_preconditioner,seconds_linear,seconds_line_search,"
                "seconds_total\n";
        for (const auto& l : keep) log_ << l << "\n";
        log_.flush();
      }
    }
  }
  Teuchos::broadcast(comm, 0, &ok);
  if (!ok) throw InputError(scene_file + ": Output: cannot create results folder '" + dir_ + "': " + err, InputErrorKind::File);
  // Step files already on disk from before the restart point belong to the run's history.
  if (restart_step >= 0 && hdf5_)
    for (int k = 0; k <= restart_step; ++k)
      if (fs::exists(step_file(k))) written_.emplace_back(k, static_cast<double>(k) / scene.steps());
}

std::string Output::step_file(int step) const {
  std::ostringstream os;
  os << dir_ << "/step_" << std::setw(6) << std::setfill('0') << step << ".h5";
  return os.str();
}

void Output::write_mesh() {
  if (!hdf5_) return;
  const ElasticSystem& sys = scene_.system();
  const Mesh& m = sys.mesh();
  MPI_Comm comm = raw_comm(*sys.comm());
  const std::string path = dir_ + "/mesh.h5", tmp = path + ".tmp";
  const long long n_owned = static_cast<long long>(m.n_owned_nodes), e_owned = static_cast<long long>(m.n_owned_elements);
  const long long first_node = n_owned > 0 ? m.node_gid[0] : 0, first_el = e_owned > 0 ? m.element_gid[0] : 0;
  // Slab partitions own contiguous ranges of global ids: checked, since the hyperslabs rely on it.
  if (n_owned > 0 && m.node_gid[n_owned - 1] - first_node + 1 != n_owned)
    throw std::logic_error("output: owned nodes are not a contiguous range of global ids");
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
  auto C = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.conn);
  std::vector<double> xyz(3 * n_owned);
  for (long long n = 0; n < n_owned; ++n)
    for (int d = 0; d < 3; ++d) xyz[3 * n + d] = X(n, d);
  const int npe = nodes_per_element(m.type);
  std::vector<long long> conn(npe * e_owned);
  for (long long e = 0; e < e_owned; ++e)
    for (int a = 0; a < npe; ++a) conn[npe * e + a] = m.node_gid[C(e, a)];
  {
    H5 file(create_parallel(tmp, comm), H5Fclose, "create " + tmp);
    write_rows(file.id, "/coordinates", H5T_NATIVE_DOUBLE, m.global_nodes, 3, first_node, n_owned, xyz.data(), tmp);
    write_rows(file.id, "/connectivity", H5T_NATIVE_LLONG, m.global_elements, npe, first_el, e_owned, conn.data(), tmp);
  }
  MPI_Barrier(comm);
  if (root_) fs::rename(tmp, path);
  MPI_Barrier(comm);
}

void Output::write_step(int step, double load, const Vector& u) {
  if (!hdf5_) return;
  const ElasticSystem& sys = scene_.system();
  const Mesh& m = sys.mesh();
  MPI_Comm comm = raw_comm(*sys.comm());
  std::vector<double> psi, J;
  sys.element_fields(u, psi, J);
  const long long n_owned = static_cast<long long>(m.n_owned_nodes), e_owned = static_cast<long long>(m.n_owned_elements);
  const long long first_node = n_owned > 0 ? m.node_gid[0] : 0, first_el = e_owned > 0 ? m.element_gid[0] : 0;
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
  auto uv = u.getLocalViewHost(Tpetra::Access::ReadOnly);
  std::vector<double> disp(3 * n_owned), pos(3 * n_owned);
  for (long long n = 0; n < n_owned; ++n)
    for (int d = 0; d < 3; ++d) {
      disp[3 * n + d] = uv(3 * n + d, 0);
      pos[3 * n + d] = X(n, d) + uv(3 * n + d, 0);
    }
  const std::string path = step_file(step), tmp = path + ".tmp";
  {
    H5 file(create_parallel(tmp, comm), H5Fclose, "create " + tmp);
    write_rows(file.id, "/displacement", H5T_NATIVE_DOUBLE, m.global_nodes, 3, first_node, n_owned, disp.data(), tmp);
    write_rows(file.id, "/position", H5T_NATIVE_DOUBLE, m.global_nodes, 3, first_node, n_owned, pos.data(), tmp);
    write_rows(file.id, "/J", H5T_NATIVE_DOUBLE, m.global_elements, 1, first_el, e_owned, J.data(), tmp);
    write_rows(file.id, "/energy_density", H5T_NATIVE_DOUBLE, m.global_elements, 1, first_el, e_owned, psi.data(), tmp);
    write_attribute(file.id, "load", load);
    write_attribute(file.id, "step", step);
  }
  MPI_Barrier(comm);
  if (root_) fs::rename(tmp, path);
  written_.emplace_back(step, load);
  if (root_) write_xdmf();
  MPI_Barrier(comm);
}

void Output::write_xdmf() const {
  const Mesh& m = scene_.system().mesh();
  const int npe = nodes_per_element(m.type);
  const std::string topo = m.type == ElementType::Hex8 ? "Hexahedron" : "Tetrahedron";
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"" << name_ << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& [step, load] : written_) {
    const std::string f = fs::path(step_file(step)).filename().string();
    x << "   <Grid Name=\"step " << step << "\" GridType=\"Uniform\">\n"
      << "    <Time Value=\"" << load << "\"/>\n"
      << "    <Topology TopologyType=\"" << topo << "\" NumberOfElements=\"" << m.global_elements << "\">\n"
      << "     <DataItem Dimensions=\"" << m.global_elements << " " << npe
      << "\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">mesh.h5:/connectivity</DataItem>\n"
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
    x << "   </Grid>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  const std::string path = dir_ + "/" + name_ + ".xdmf", tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << x.str();
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  fs::rename(tmp, path);
}

void Output::log(const StepRecord& r) {
  if (!root_) return;
  const auto& s = r.solve;
  log_ << std::setprecision(10) << r.step << "," << r.load << "," << r.cuts << "," << s.newton_iterations << ","
       << s.linear_iterations << "," << s.initial_residual << "," << s.final_residual << "," << r.totals.energy << ","
       << r.volume_ratio << "," << r.totals.min_J << "," << r.totals.inverted << "," << s.seconds_assembly << ","
       << s.seconds_preconditioner << "," << s.seconds_linear << "," << s.seconds_line_search << "," << s.seconds_total
       << "\n";
  log_.flush();
}

void Output::write_checkpoint(int step, double load, const Vector& u) {
  const ElasticSystem& sys = scene_.system();
  const Mesh& m = sys.mesh();
  MPI_Comm comm = raw_comm(*sys.comm());
  const long long n_owned = static_cast<long long>(m.n_owned_nodes);
  const long long first_node = n_owned > 0 ? m.node_gid[0] : 0;
  auto uv = u.getLocalViewHost(Tpetra::Access::ReadOnly);
  std::vector<double> disp(uv.data(), uv.data() + 3 * n_owned);
  const std::string path = checkpoint_file(), tmp = path + ".tmp";
  {
    H5 file(create_parallel(tmp, comm), H5Fclose, "create " + tmp);
    write_rows(file.id, "/displacement", H5T_NATIVE_DOUBLE, m.global_nodes, 3, first_node, n_owned, disp.data(), tmp);
    write_attribute(file.id, "step", step);
    write_attribute(file.id, "load", load);
    write_attribute(file.id, "global_nodes", static_cast<double>(m.global_nodes));
    write_attribute(file.id, "steps", scene_.steps());
  }
  MPI_Barrier(comm);
  // The rename is atomic: a kill at any point leaves either the old checkpoint or the new one.
  if (root_) fs::rename(tmp, path);
  MPI_Barrier(comm);
}

Output::Checkpoint Output::read_checkpoint(const std::string& path, const Scene& scene, Vector& u) {
  const ElasticSystem& sys = scene.system();
  const Mesh& m = sys.mesh();
  MPI_Comm comm = raw_comm(*sys.comm());
  int exists = fs::exists(path) ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &exists, 1, MPI_INT, MPI_MIN, comm);
  if (!exists) throw InputError("restart file '" + path + "' does not exist", InputErrorKind::File);
  H5 fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "file access properties");
  H5Pset_fapl_mpio(fapl.id, comm, MPI_INFO_NULL);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // we report errors ourselves
  const hid_t fid = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.id);
  if (fid < 0) throw InputError("restart file '" + path + "' is not a readable HDF5 file", InputErrorKind::File);
  H5 file(fid, H5Fclose, "open " + path);
  auto attribute = [&](const char* name) {
    double v = -1.0;
    const hid_t a = H5Aopen(file.id, name, H5P_DEFAULT);
    if (a < 0) throw InputError("restart file '" + path + "' has no '" + name + "' attribute", InputErrorKind::File);
    H5Aread(a, H5T_NATIVE_DOUBLE, &v);
    H5Aclose(a);
    return v;
  };
  Checkpoint c;
  c.step = static_cast<int>(attribute("step"));
  c.load = attribute("load");
  const long long nodes = static_cast<long long>(attribute("global_nodes"));
  if (nodes != m.global_nodes)
    throw InputError("restart file '" + path + "' was written for a mesh of " + std::to_string(nodes) +
                         " nodes; this scene has " + std::to_string(m.global_nodes),
                     InputErrorKind::File);
  const int steps = static_cast<int>(attribute("steps"));
  if (steps != scene.steps())
    throw InputError("restart file '" + path + "' was written for " + std::to_string(steps) +
                         " load steps; this scene has " + std::to_string(scene.steps()),
                     InputErrorKind::File);
  const long long n_owned = static_cast<long long>(m.n_owned_nodes);
  const long long first_node = n_owned > 0 ? m.node_gid[0] : 0;
  H5 dset(H5Dopen2(file.id, "/displacement", H5P_DEFAULT), H5Dclose, path + ": /displacement");
  H5 space(H5Dget_space(dset.id), H5Sclose, "dataspace");
  hsize_t start[2] = {static_cast<hsize_t>(first_node), 0}, cnt[2] = {static_cast<hsize_t>(n_owned), 3};
  H5 mem(H5Screate_simple(2, cnt, nullptr), H5Sclose, "memspace");
  if (n_owned > 0) {
    H5Sselect_hyperslab(space.id, H5S_SELECT_SET, start, nullptr, cnt, nullptr);
  } else {
    H5Sselect_none(space.id);
    H5Sselect_none(mem.id);
  }
  std::vector<double> disp(3 * n_owned);
  if (H5Dread(dset.id, H5T_NATIVE_DOUBLE, mem.id, space.id, H5P_DEFAULT, disp.data()) < 0)
    throw InputError("restart file '" + path + "': cannot read /displacement", InputErrorKind::File);
  auto uv = u.getLocalViewHost(Tpetra::Access::OverwriteAll);
  for (long long i = 0; i < 3 * n_owned; ++i) uv(i, 0) = disp[i];
  return c;
}

}  // namespace sinew
