#include <mpm/geometry/triangle_mesh.h>

#include <mpm/core/error.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <utility>

namespace mpm::geometry {

namespace {

std::string lowercase_extension(const std::string& file) {
  std::string extension = std::filesystem::path(file).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

[[noreturn]] void fail(const std::string& where, const std::string& problem) {
  throw InputError(where + ": " + problem);
}

std::string at_line(const std::string& file, int line) { return file + ":" + std::to_string(line); }

std::int32_t vertex_count(const TriangleMesh& mesh) { return static_cast<std::int32_t>(mesh.vertices.size()); }

//! The 0-based vertex index of one OBJ face corner "i", "i/t", "i//n" or "i/t/n"; negative i
//! counts back from the last vertex read so far.
std::int32_t obj_corner(const std::string& token, std::int32_t vertices_so_far, const std::string& where) {
  const std::string index_text = token.substr(0, token.find('/'));
  std::int32_t index = 0;
  const auto result = std::from_chars(index_text.data(), index_text.data() + index_text.size(), index);
  if (result.ec != std::errc() || result.ptr != index_text.data() + index_text.size() || index == 0)
    fail(where, "face corner '" + token + "' is no nonzero vertex index");
  const std::int32_t zero_based = index > 0 ? index - 1 : vertices_so_far + index;
  if (zero_based < 0 || zero_based >= vertices_so_far)
    fail(where, "face corner '" + token + "' refers to a missing vertex (" + std::to_string(vertices_so_far) +
                    " vertices read so far)");
  return zero_based;
}

TriangleMesh read_obj(const std::string& file, std::istream& in) {
  TriangleMesh mesh;
  std::string line;
  for (int line_number = 1; std::getline(in, line); ++line_number) {
    std::istringstream tokens(line);
    std::string tag;
    tokens >> tag;
    if (tag == "v") {
      Vec<3> x;
      if (!(tokens >> x[0] >> x[1] >> x[2])) fail(at_line(file, line_number), "expected 'v x y z'");
      mesh.vertices.push_back(x);
    } else if (tag == "f") {
      std::vector<std::int32_t> corners;
      for (std::string token; tokens >> token;)
        corners.push_back(obj_corner(token, vertex_count(mesh), at_line(file, line_number)));
      if (corners.size() < 3) fail(at_line(file, line_number), "a face needs at least 3 corners");
      // A convex polygon is the fan of triangles around its first corner.
      for (std::size_t k = 1; k + 1 < corners.size(); ++k)
        mesh.triangles.push_back({corners[0], corners[k], corners[k + 1]});
    }
  }
  return mesh;
}

//! Adds x to the mesh unless an equal vertex exists; returns its index.
std::int32_t weld(TriangleMesh& mesh, std::map<std::array<double, 3>, std::int32_t>& index_of, const Vec<3>& x) {
  const auto [it, inserted] = index_of.try_emplace({x[0], x[1], x[2]}, vertex_count(mesh));
  if (inserted) mesh.vertices.push_back(x);
  return it->second;
}

float little_endian_float(const char* bytes) {
  std::uint32_t bits = 0;
  for (int i = 3; i >= 0; --i) bits = (bits << 8) | static_cast<unsigned char>(bytes[i]);
  return std::bit_cast<float>(bits);
}

//! Binary STL: an 80-byte header, a uint32 count, then 50 bytes per triangle (normal,
//! three vertices as little-endian float32, a uint16 attribute).
TriangleMesh read_binary_stl(const std::string& bytes) {
  TriangleMesh mesh;
  std::map<std::array<double, 3>, std::int32_t> index_of;
  const std::size_t count = (bytes.size() - 84) / 50;
  for (std::size_t t = 0; t < count; ++t) {
    const char* record = bytes.data() + 84 + 50 * t;
    std::array<std::int32_t, 3> triangle{};
    for (int corner = 0; corner < 3; ++corner) {
      const char* xyz = record + 12 * (corner + 1);
      const Vec<3> x(little_endian_float(xyz), little_endian_float(xyz + 4), little_endian_float(xyz + 8));
      triangle[corner] = weld(mesh, index_of, x);
    }
    mesh.triangles.push_back(triangle);
  }
  return mesh;
}

//! ASCII STL: every `vertex x y z` line adds a corner; three corners make a facet.
TriangleMesh read_ascii_stl(const std::string& file, const std::string& text) {
  TriangleMesh mesh;
  std::map<std::array<double, 3>, std::int32_t> index_of;
  std::istringstream in(text);
  std::string line;
  std::vector<std::int32_t> corners;
  for (int line_number = 1; std::getline(in, line); ++line_number) {
    std::istringstream tokens(line);
    std::string tag;
    tokens >> tag;
    if (tag != "vertex") continue;
    Vec<3> x;
    if (!(tokens >> x[0] >> x[1] >> x[2])) fail(at_line(file, line_number), "expected 'vertex x y z'");
    corners.push_back(weld(mesh, index_of, x));
    if (corners.size() == 3) {
      mesh.triangles.push_back({corners[0], corners[1], corners[2]});
      corners.clear();
    }
  }
  if (!corners.empty()) fail(file, "the last facet has " + std::to_string(corners.size()) + " vertices, expected 3");
  return mesh;
}

TriangleMesh read_stl(const std::string& file, std::istream& in) {
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (bytes.size() >= 84) {
    std::uint32_t count = 0;
    for (int i = 3; i >= 0; --i) count = (count << 8) | static_cast<unsigned char>(bytes[80 + i]);
    if (bytes.size() == 84 + 50 * std::size_t(count)) return read_binary_stl(bytes);
  }
  if (bytes.rfind("solid", 0) == 0) return read_ascii_stl(file, bytes);
  fail(file, "neither a binary STL (size 84 + 50 * triangle count) nor an ASCII STL ('solid ...')");
}

}  // namespace

bool is_triangle_mesh_file(const std::string& file) {
  const std::string extension = lowercase_extension(file);
  return extension == ".obj" || extension == ".stl";
}

TriangleMesh read_triangle_mesh(const std::string& file) {
  if (!is_triangle_mesh_file(file))
    fail(file,
         "unknown mesh extension '" + std::filesystem::path(file).extension().string() + "' (expected .obj or .stl)");
  std::ifstream in(file, std::ios::binary);
  if (!in) fail(file, "cannot open the mesh file");
  TriangleMesh mesh = lowercase_extension(file) == ".obj" ? read_obj(file, in) : read_stl(file, in);
  if (mesh.triangles.empty()) fail(file, "the mesh holds no triangle");
  return mesh;
}

void check_closed(const TriangleMesh& mesh, const std::string& file) {
  // Each undirected edge, counted over the triangles; a degenerate triangle (a repeated
  // vertex) encloses nothing and is skipped.
  std::map<std::pair<std::int32_t, std::int32_t>, int> uses;
  for (const auto& t : mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(t[k], t[(k + 1) % 3])];
  }
  const auto point = [&](std::int32_t v) {
    std::ostringstream text;
    text.precision(9);
    text << "(" << mesh.vertices[v][0] << ", " << mesh.vertices[v][1] << ", " << mesh.vertices[v][2] << ")";
    return text.str();
  };
  for (const auto& [edge, count] : uses)
    if (count % 2 != 0)
      fail(file, "the mesh is not closed: its edge from " + point(edge.first) + " to " + point(edge.second) +
                     " belongs to " + std::to_string(count) + (count == 1 ? " triangle" : " triangles") +
                     " (a closed surface shares every edge between two triangles); a level set needs the "
                     "inside of a closed surface");
}

}  // namespace mpm::geometry
