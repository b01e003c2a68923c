#include "io/gmsh_reader.hpp"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

namespace bfemp {
namespace {

std::string read_whole_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f)
    throw std::runtime_error("mesh file '" + path + "': cannot open (" +
                             std::strerror(errno) + ")");
  std::string text;
  char buf[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw std::runtime_error("mesh file '" + path + "': read error");
  return text;
}

// Whitespace-separated tokens with line tracking for error messages.
class MshCursor {
 public:
  MshCursor(std::string path, std::string text) : path_(std::move(path)), text_(std::move(text)) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("mesh file '" + path_ + "' line " + std::to_string(line_) + ": " +
                             what);
  }
  bool at_end() {
    skip_space(true);
    return pos_ >= text_.size();
  }
  // True if the current line has another token (does not consume newlines).
  bool line_has_more() {
    skip_space(false);
    return pos_ < text_.size() && text_[pos_] != '\n';
  }
  template <class T>
  T number(const char* what, const char* kind) {
    const std::string_view t = token(what);
    T v{};
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size())
      fail(std::string("expected ") + kind + " (" + what + "), found '" + std::string(t) + "'");
    return v;
  }
  std::string_view token(const char* what) {
    if (at_end()) fail(std::string("unexpected end of file (truncated?) while reading ") + what);
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    return std::string_view(text_).substr(start, pos_ - start);
  }
  long long integer(const char* what) { return number<long long>(what, "an integer"); }
  double real(const char* what) { return number<double>(what, "a number"); }
  // A double-quoted name (may contain spaces).
  std::string quoted(const char* what) {
    if (at_end() || text_[pos_] != '"') fail(std::string("expected a quoted ") + what);
    const std::size_t end = text_.find('"', pos_ + 1);
    if (end == std::string::npos || text_.find('\n', pos_) < end)
      fail(std::string("unterminated quoted ") + what);
    std::string s = text_.substr(pos_ + 1, end - pos_ - 1);
    pos_ = end + 1;
    return s;
  }
  void expect(std::string_view want) {
    const std::string_view t = token(std::string(want).c_str());
    if (t != want) fail("expected '" + std::string(want) + "', found '" + std::string(t) + "'");
  }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
  void skip_space(bool newlines) {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      if (text_[pos_] == '\n') {
        if (!newlines) return;
        ++line_;
      }
      ++pos_;
    }
  }
  std::string path_;
  std::string text_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
};

using EntityKey = std::pair<int, int>;  // (dimension, tag)

struct RawMesh {
  std::map<EntityKey, std::string> physical_names;
  std::map<EntityKey, std::vector<int>> entity_physicals;
  std::unordered_map<long long, long long> node_index;  // node tag -> raw index
  std::vector<double> xyz;                               // 3 per raw node
  std::vector<long long> cells;                          // raw node indices
  std::map<EntityKey, std::vector<long long>> physical_nodes;  // raw indices
  std::map<long long, long long> element_type_counts;
  bool have_nodes = false, have_elements = false;
};

void read_format(MshCursor& in) {
  const std::string version(in.token("MSH version"));
  if (version != "4.1")
    in.fail("expected MSH 4.1 ASCII, found MSH version " + version +
            " (re-export with Mesh.MshFileVersion = 4.1)");
  const long long file_type = in.integer("MSH file-type");
  if (file_type != 0)
    in.fail("expected MSH 4.1 ASCII, found binary file-type " + std::to_string(file_type) +
            " (re-export with Mesh.Binary = 0)");
  in.integer("MSH data-size");
  in.expect("$EndMeshFormat");
}

void read_physical_names(MshCursor& in, RawMesh& raw) {
  const long long n = in.integer("number of physical names");
  for (long long i = 0; i < n; ++i) {
    const int d = static_cast<int>(in.integer("physical dimension"));
    const int tag = static_cast<int>(in.integer("physical tag"));
    raw.physical_names[{d, tag}] = in.quoted("physical name");
  }
  in.expect("$EndPhysicalNames");
}

void read_entities(MshCursor& in, RawMesh& raw) {
  long long counts[4];
  for (long long& c : counts) c = in.integer("number of entities");
  for (int d = 0; d < 4; ++d)
    for (long long i = 0; i < counts[d]; ++i) {
      const int tag = static_cast<int>(in.integer("entity tag"));
      for (int k = 0; k < (d == 0 ? 3 : 6); ++k) in.real("entity coordinates");
      const long long n_phys = in.integer("number of physical tags");
      std::vector<int>& phys = raw.entity_physicals[{d, tag}];
      for (long long k = 0; k < n_phys; ++k)
        phys.push_back(static_cast<int>(in.integer("physical tag")));
      if (d > 0) {
        const long long n_bound = in.integer("number of bounding entities");
        for (long long k = 0; k < n_bound; ++k) in.integer("bounding entity tag");
      }
    }
  in.expect("$EndEntities");
}

void read_nodes(MshCursor& in, RawMesh& raw) {
  const long long n_blocks = in.integer("number of node blocks");
  const long long n_nodes = in.integer("number of nodes");
  in.integer("min node tag");
  in.integer("max node tag");
  if (n_blocks < 0 || n_nodes < 0) in.fail("negative node count");
  raw.node_index.reserve(static_cast<std::size_t>(n_nodes));
  raw.xyz.reserve(3 * static_cast<std::size_t>(n_nodes));
  std::vector<long long> tags;
  for (long long b = 0; b < n_blocks; ++b) {
    const long long entity_dim = in.integer("node block entity dimension");
    in.integer("node block entity tag");
    const long long parametric = in.integer("node block parametric flag");
    const long long count = in.integer("number of nodes in block");
    if (count < 0) in.fail("negative number of nodes in block");
    tags.resize(static_cast<std::size_t>(count));
    for (long long& t : tags) t = in.integer("node tag");
    const long long n_param = parametric ? entity_dim : 0;
    for (long long t : tags) {
      const long long index = static_cast<long long>(raw.node_index.size());
      if (!raw.node_index.emplace(t, index).second)
        in.fail("duplicate node tag " + std::to_string(t));
      for (int k = 0; k < 3; ++k) raw.xyz.push_back(in.real("node coordinate"));
      for (long long k = 0; k < n_param; ++k) in.real("node parametric coordinate");
    }
  }
  if (static_cast<long long>(raw.node_index.size()) != n_nodes)
    in.fail("$Nodes header announces " + std::to_string(n_nodes) + " nodes, blocks hold " +
            std::to_string(raw.node_index.size()));
  in.expect("$EndNodes");
  raw.have_nodes = true;
}

void read_elements(MshCursor& in, RawMesh& raw, int dim) {
  if (!raw.have_nodes) in.fail("$Elements section before $Nodes");
  const long long n_blocks = in.integer("number of element blocks");
  in.integer("number of elements");
  in.integer("min element tag");
  in.integer("max element tag");
  const long long cell_type = dim == 2 ? 2 : 4;
  std::vector<long long> nodes;
  for (long long b = 0; b < n_blocks; ++b) {
    const int entity_dim = static_cast<int>(in.integer("element block entity dimension"));
    const int entity_tag = static_cast<int>(in.integer("element block entity tag"));
    const long long type = in.integer("element type");
    const long long count = in.integer("number of elements in block");
    if (count < 0) in.fail("negative number of elements in block");
    raw.element_type_counts[type] += count;
    const auto phys_it = raw.entity_physicals.find({entity_dim, entity_tag});
    for (long long e = 0; e < count; ++e) {
      in.integer("element tag");
      nodes.clear();
      while (in.line_has_more()) {
        const long long tag = in.integer("element node tag");
        const auto it = raw.node_index.find(tag);
        if (it == raw.node_index.end()) in.fail("element references unknown node tag " + std::to_string(tag));
        nodes.push_back(it->second);
      }
      if (in.at_end()) in.fail("unexpected end of file (truncated?) in $Elements");
      if (nodes.empty()) in.fail("element without node tags");
      if (type == cell_type) {
        if (nodes.size() != static_cast<std::size_t>(dim + 1))
          in.fail("element of type " + std::to_string(type) + " has " +
                  std::to_string(nodes.size()) + " nodes, expected " + std::to_string(dim + 1));
        raw.cells.insert(raw.cells.end(), nodes.begin(), nodes.end());
      }
      if (phys_it != raw.entity_physicals.end())
        for (int phys : phys_it->second) {
          std::vector<long long>& set = raw.physical_nodes[{entity_dim, phys}];
          set.insert(set.end(), nodes.begin(), nodes.end());
        }
    }
  }
  in.expect("$EndElements");
  raw.have_elements = true;
}

void skip_section(MshCursor& in, std::string_view header) {
  const std::string end = "$End" + std::string(header.substr(1));
  while (in.token(end.c_str()) != end) {
  }
}

}  // namespace

MeshData read_gmsh_msh4(const std::string& path, int dim) {
  if (dim != 2 && dim != 3)
    throw std::invalid_argument("read_gmsh_msh4('" + path + "'): dim = " + std::to_string(dim) +
                                ", expected 2 or 3");
  MshCursor in(path, read_whole_file(path));
  if (in.at_end()) in.fail("empty file, expected MSH 4.1 ASCII");
  RawMesh raw;
  const std::string first(in.token("$MeshFormat"));
  if (first != "$MeshFormat")
    in.fail("expected MSH 4.1 ASCII starting with '$MeshFormat', found '" + first + "'");
  read_format(in);
  while (!in.at_end()) {
    const std::string_view section = in.token("section header");
    if (section == "$PhysicalNames") read_physical_names(in, raw);
    else if (section == "$Entities") read_entities(in, raw);
    else if (section == "$Nodes") read_nodes(in, raw);
    else if (section == "$Elements") read_elements(in, raw, dim);
    else if (section.size() > 1 && section[0] == '$' && section.substr(0, 4) != "$End")
      skip_section(in, section);
    else in.fail("expected a section header '$...', found '" + std::string(section) + "'");
  }
  if (!raw.have_nodes || !raw.have_elements)
    throw std::runtime_error("mesh file '" + path + "': no " +
                             (raw.have_nodes ? "$Elements" : "$Nodes") +
                             " section (truncated file?)");
  if (raw.cells.empty()) {
    std::string present;
    for (const auto& [type, n] : raw.element_type_counts)
      present += (present.empty() ? "" : ", ") + std::to_string(type);
    throw std::runtime_error("mesh file '" + path + "': no " +
                             (dim == 2 ? "3-node triangle (type 2)" : "4-node tetrahedron (type 4)") +
                             " elements for dim = " + std::to_string(dim) +
                             "; element types present: " + (present.empty() ? "none" : present));
  }

  MeshData mesh;
  mesh.dim = dim;
  const std::size_t n_raw = raw.xyz.size() / 3;
  mesh.coords.resize(n_raw * dim);
  for (std::size_t i = 0; i < n_raw; ++i)
    for (int k = 0; k < dim; ++k) mesh.coords[i * dim + k] = raw.xyz[3 * i + k];
  mesh.cells = std::move(raw.cells);
  for (const auto& [key, name] : raw.physical_names) mesh.node_sets[name];  // named, maybe empty
  for (auto& [key, nodes] : raw.physical_nodes) {
    const auto name_it = raw.physical_names.find(key);
    const std::string name = name_it != raw.physical_names.end()
                                 ? name_it->second
                                 : "physical_" + std::to_string(key.first) + "_" +
                                       std::to_string(key.second);
    std::vector<long long>& set = mesh.node_sets[name];
    set.insert(set.end(), nodes.begin(), nodes.end());
  }
  finalize_mesh(mesh, path);
  return mesh;
}

}  // namespace bfemp
