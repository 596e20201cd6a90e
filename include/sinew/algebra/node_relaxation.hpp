// Settings and totals of a nonlinear Gauss-Seidel pass over a few nodes (ElasticTerm::relax,
// System::relax_nodes): the nonlinear elimination of a Newton iterate's residual hot spots.
#pragma once

namespace sinew {

struct NodeRelaxationSettings {
  int sweeps = 2;            // passes over the nodes
  int iterations = 8;        // damped Newton iterations per node and pass, at most
  double reduction = 0.05;   // a node is done when its force fell by this factor within the pass
  double tolerance = 0.0;    // ... or below this (absolute)
};
struct NodeRelaxationTotals {
  long long nodes = 0;       // nodes moved
  long long iterations = 0;  // local Newton iterations
  double decrease = 0.0;     // energy decrease the local solves computed (this rank's)
};

}  // namespace sinew
