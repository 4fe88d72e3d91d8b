// Makes benchmark inputs from real meshes: imports any svokit-readable mesh, optionally refines it
// by Loop subdivision (OpenMesh) and appends other meshes scaled into its bounding box, and writes
// OBJ or PLY (OpenMesh's writers) so peers such as vdb_tool can read the same file.
//
//   bench_mesh IN OUT.{obj,ply} [--loop N] [--add OTHER]... [--binary]

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <cstdio>
#include <string>
#include <vector>

#include "svokit/formats/mesh_import.hpp"

namespace {

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

// Appends `mesh` to `out`, mapping its bounds onto `target` (when given) — e.g. a room around a
// statue, so the scene mixes huge and tiny triangles.
void Append(const svokit::Mesh& mesh, const svokit::Box3d* target, OmMesh& out) {
  const svokit::Box3d b = mesh.Bounds();
  std::vector<OmMesh::VertexHandle> handles;
  for (const svokit::Vec3d& p : mesh.positions) {
    svokit::Vec3d q = p;
    if (target) {
      for (int a = 0; a < 3; ++a) {
        const double e = b.hi[a] - b.lo[a];
        q[a] =
            target->lo[a] + (e > 0 ? (p[a] - b.lo[a]) / e : 0.5) * (target->hi[a] - target->lo[a]);
      }
    }
    handles.push_back(out.add_vertex(
        OmMesh::Point(static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z))));
  }
  for (const svokit::Triangle& t : mesh.triangles) {
    out.add_face(handles[t[0]], handles[t[1]], handles[t[2]]);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: bench_mesh IN OUT.{obj,ply} [--loop N] [--add OTHER]... [--binary]\n");
    return 2;
  }
  std::vector<std::string> extra;
  int loops = 0;
  bool binary = false;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--loop" && i + 1 < argc)
      loops = std::stoi(argv[++i]);
    else if (a == "--add" && i + 1 < argc)
      extra.push_back(argv[++i]);
    else if (a == "--binary")
      binary = true;
    else {
      std::fprintf(stderr, "bench_mesh: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  auto mesh = svokit::ImportMesh(argv[1]);
  if (!mesh.ok()) {
    std::fprintf(stderr, "bench_mesh: %s\n", mesh.status().message().c_str());
    return 2;
  }
  OmMesh out;
  Append(*mesh, nullptr, out);
  if (loops > 0) {
    OpenMesh::Subdivider::Uniform::LoopT<OmMesh> loop;
    loop.attach(out);
    loop(static_cast<std::size_t>(loops));
    loop.detach();
  }
  // Extra meshes are scaled to enclose the (refined) first one with a 10% margin.
  svokit::Box3d box = mesh->Bounds();
  const svokit::Vec3d margin = box.extent() * 0.1;
  box = {box.lo - margin, box.hi + margin};
  for (const std::string& path : extra) {
    auto other = svokit::ImportMesh(path);
    if (!other.ok()) {
      std::fprintf(stderr, "bench_mesh: %s\n", other.status().message().c_str());
      return 2;
    }
    Append(*other, &box, out);
  }
  OpenMesh::IO::Options options;
  if (binary) options += OpenMesh::IO::Options::Binary;
  if (!OpenMesh::IO::write_mesh(out, argv[2], options)) {
    std::fprintf(stderr, "bench_mesh: cannot write %s\n", argv[2]);
    return 3;
  }
  std::printf("%s: %zu triangles\n", argv[2], out.n_faces());
  return 0;
}
