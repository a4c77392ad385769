// CGAL's Surface_mesh_simplification::edge_collapse (CGAL's default Lindstrom-Turk cost and
// placement) of a closed triangle mesh down to a target face count, for isolab's `decimation`
// experiment. Usage: cgal_edge_collapse IN.obj TARGET_FACES OUT.obj REPEATS
// Prints one JSON line: {"ms": [...], "vertices": V, "triangles": F}; times the collapse only
// (each repeat collapses a fresh copy of the input). Built by tests/reference/run.sh setup.
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/boost/graph/IO/polygon_mesh_io.h>

#include <chrono>
#include <cstdlib>
#include <iostream>
#include <vector>

using Kernel = CGAL::Simple_cartesian<double>;
using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMS = CGAL::Surface_mesh_simplification;

int main(int argc, char** argv) {
  if (argc != 5) {
    std::cerr << "usage: cgal_edge_collapse IN.obj TARGET_FACES OUT.obj REPEATS\n";
    return 2;
  }
  Mesh input;
  if (!CGAL::IO::read_polygon_mesh(argv[1], input) || !CGAL::is_triangle_mesh(input)) {
    std::cerr << argv[1] << ": not a readable triangle mesh\n";
    return 1;
  }
  const long target = std::atol(argv[2]);
  const int repeats = std::max(1, std::atoi(argv[4]));
  if (target <= 0) {
    std::cerr << "target face count must be positive, got " << argv[2] << "\n";
    return 2;
  }
  // On a closed triangle mesh E = 3F/2; the predicate stops once fewer than this many edges
  // remain, so the collapse ends at the target face count (each collapse removes 2 faces).
  SMS::Count_stop_predicate<Mesh> stop(static_cast<std::size_t>(3 * target / 2 + 1));
  Mesh mesh;
  std::vector<double> ms;
  for (int r = 0; r < repeats; ++r) {
    mesh = input;
    auto t = std::chrono::steady_clock::now();
    SMS::edge_collapse(mesh, stop);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count());
  }
  mesh.collect_garbage();
  if (!CGAL::IO::write_polygon_mesh(argv[3], mesh, CGAL::parameters::stream_precision(17))) {
    std::cerr << argv[3] << ": cannot write\n";
    return 1;
  }
  std::cout << "{\"ms\": [";
  for (std::size_t i = 0; i < ms.size(); ++i) std::cout << (i ? ", " : "") << ms[i];
  std::cout << "], \"vertices\": " << mesh.number_of_vertices() << ", \"triangles\": " << mesh.number_of_faces() << "}\n";
  return 0;
}
