// CGAL Mesh_3 on a labeled image: the peer of isolab's `lattice-cleaving` (issue 65).
//
//   cgal_labeled_image LABELS.raw NX NY NZ FACET_SIZE CELL_SIZE OUT.txt
//
// LABELS.raw holds NX * NY * NZ unsigned bytes, x fastest, one per voxel of unit spacing (label
// 0 the background, which Mesh_3 leaves unmeshed). The domain is CGAL's labeled image domain
// (Labeled_mesh_domain_3::create_labeled_image_mesh_domain); the criteria are the labeled-image
// example's shape bounds (facet angle 30 degrees, radius-edge ratio 3) with the given facet and
// cell sizes and a facet distance of FACET_SIZE / 4; no optimisation step runs (make_mesh_3's
// defaults: perturbation and exudation on, ODT and Lloyd off). OUT.txt gets the vertices used by
// the complex's cells ("v x y z", voxel coordinates: voxel i's centre at i) and the cells
// ("t a b c d label", positively oriented). Stdout: one JSON line with the time of make_mesh_3
// alone (ms), the counts, and the CGAL version.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/ImageIO.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/version.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Labeled_mesh_domain_3<K> Mesh_domain;
typedef CGAL::Mesh_triangulation_3<Mesh_domain, CGAL::Default, CGAL::Sequential_tag>::type Tr;
typedef CGAL::Mesh_complex_3_in_triangulation_3<Tr> C3t3;
typedef CGAL::Mesh_criteria_3<Tr> Mesh_criteria;
namespace params = CGAL::parameters;

int main(int argc, char* argv[]) {
  if (argc != 8) {
    std::cerr << "usage: cgal_labeled_image LABELS.raw NX NY NZ FACET_SIZE CELL_SIZE OUT.txt\n";
    return 2;
  }
  const std::size_t nx = std::stoul(argv[2]), ny = std::stoul(argv[3]), nz = std::stoul(argv[4]);
  const double facet_size = std::stod(argv[5]), cell_size = std::stod(argv[6]);
  std::vector<unsigned char> labels(nx * ny * nz);
  std::ifstream in(argv[1], std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(labels.data()), labels.size())) {
    std::cerr << argv[1] << ": not " << labels.size() << " bytes\n";
    return 1;
  }
  _image* raw = ::_createImage(nx, ny, nz, 1, 1.0, 1.0, 1.0, 1, WK_FIXED, SGN_UNSIGNED);
  std::memcpy(raw->data, labels.data(), labels.size());
  CGAL::Image_3 image(raw);
  Mesh_domain domain = Mesh_domain::create_labeled_image_mesh_domain(image);
  Mesh_criteria criteria(params::facet_angle = 30, params::facet_size = facet_size,
                         params::facet_distance = facet_size / 4, params::cell_radius_edge_ratio = 3,
                         params::cell_size = cell_size);
  const auto start = std::chrono::steady_clock::now();
  C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  std::map<Tr::Vertex_handle, std::size_t> index;
  std::vector<Tr::Vertex_handle> order;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    for (int i = 0; i < 4; ++i) {
      auto v = c->vertex(i);
      if (index.emplace(v, order.size()).second) order.push_back(v);
    }
  }
  std::ofstream out(argv[7]);
  out.precision(9);
  for (auto v : order) {
    const auto p = v->point().point();
    out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  }
  std::size_t cells = 0;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c, ++cells) {
    out << "t " << index[c->vertex(0)] << ' ' << index[c->vertex(1)] << ' ' << index[c->vertex(2)] << ' '
        << index[c->vertex(3)] << ' ' << c3t3.subdomain_index(c) << '\n';
  }
  std::cout << "{\"make_mesh_3_ms\": " << ms << ", \"vertices\": " << order.size() << ", \"tetrahedra\": " << cells
            << ", \"cgal\": \"" << CGAL_VERSION_STR << "\"}" << std::endl;
  return 0;
}
