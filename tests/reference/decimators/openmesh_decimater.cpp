// OpenMesh's Decimater (quadric error priority, plus the normal-flipping guard as OpenMesh's own
// command-line decimater uses it) of a closed triangle mesh down to a target face count, for
// isolab's `decimation` experiment. Usage: openmesh_decimater IN.obj TARGET_FACES OUT.obj REPEATS
// Prints one JSON line: {"ms": [...], "vertices": V, "triangles": F}; times the decimation only
// (each repeat decimates a fresh copy of the input). Built by tests/reference/run.sh setup.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include <chrono>
#include <cstdlib>
#include <iostream>
#include <vector>

struct Traits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
};
using Mesh = OpenMesh::TriMesh_ArrayKernelT<Traits>;

int main(int argc, char** argv) {
  if (argc != 5) {
    std::cerr << "usage: openmesh_decimater IN.obj TARGET_FACES OUT.obj REPEATS\n";
    return 2;
  }
  omlog().disable();  // OpenMesh's chatter would mix with the JSON line
  omout().disable();
  Mesh input;
  if (!OpenMesh::IO::read_mesh(input, argv[1])) {
    std::cerr << argv[1] << ": not a readable mesh\n";
    return 1;
  }
  // The normal-flipping guard compares face normals before and after each collapse.
  input.request_face_normals();
  input.update_face_normals();
  const long target = std::atol(argv[2]);
  const int repeats = std::max(1, std::atoi(argv[4]));
  if (target <= 0) {
    std::cerr << "target face count must be positive, got " << argv[2] << "\n";
    return 2;
  }
  Mesh mesh;
  std::vector<double> ms;
  for (int r = 0; r < repeats; ++r) {
    mesh = input;
    auto t = std::chrono::steady_clock::now();
    OpenMesh::Decimater::DecimaterT<Mesh> decimater(mesh);
    OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
    OpenMesh::Decimater::ModNormalFlippingT<Mesh>::Handle flipping;
    decimater.add(quadric);
    decimater.add(flipping);
    decimater.initialize();
    decimater.decimate_to_faces(0, static_cast<size_t>(target));
    mesh.garbage_collection();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count());
  }
  OpenMesh::IO::Options options;
  if (!OpenMesh::IO::write_mesh(mesh, argv[3], options, 17)) {
    std::cerr << argv[3] << ": cannot write\n";
    return 1;
  }
  std::cout << "{\"ms\": [";
  for (std::size_t i = 0; i < ms.size(); ++i) std::cout << (i ? ", " : "") << ms[i];
  std::cout << "], \"vertices\": " << mesh.n_vertices() << ", \"triangles\": " << mesh.n_faces() << "}\n";
  return 0;
}
