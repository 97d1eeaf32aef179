#include "pipeline/readers/collada_node_graph.h"

#include <algorithm>
#include <limits>
#include <unordered_map>
#include <vector>

#include "pipeline/input_error.h"
#include "pipeline/readers/buffered_input.h"

namespace cellbake {
namespace {

constexpr std::size_t kMaxTagBytes = 4096;

std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b) {
  return a > std::numeric_limits<std::uint64_t>::max() - b ? std::numeric_limits<std::uint64_t>::max() : a + b;
}

bool blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// The value of attribute `key` in start-tag text `tag` (after the element
// name), "" when absent.
// The elements whose `count` attribute assimp reserves memory for.
bool counted_element(const std::string& element) {
  for (const char* e : {"float_array", "int_array", "Name_array", "IDREF_array", "SIDREF_array", "bool_array",
                        "token_array", "accessor", "triangles", "polylist", "polygons", "lines", "linestrips",
                        "trifans", "tristrips"})
    if (element == e) return true;
  return false;
}

// The decimal number at the start of `text` (after blanks), saturating at 2^62; 0 when none.
std::uint64_t number(const std::string& text) {
  std::uint64_t v = 0;
  std::size_t i = 0;
  while (i < text.size() && blank(text[i])) ++i;
  for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i)
    v = std::min<std::uint64_t>(v * 10 + std::uint64_t(text[i] - '0'), std::uint64_t{1} << 62);
  return v;
}

std::string attribute(const std::string& tag, std::size_t from, const std::string& key) {
  std::size_t i = from;
  while (i < tag.size()) {
    while (i < tag.size() && blank(tag[i])) ++i;
    const std::size_t name_start = i;
    while (i < tag.size() && tag[i] != '=' && !blank(tag[i]) && tag[i] != '/') ++i;
    const std::string name = tag.substr(name_start, i - name_start);
    while (i < tag.size() && blank(tag[i])) ++i;
    if (i >= tag.size() || tag[i] != '=') {
      if (i == name_start) ++i;  // a stray byte
      continue;
    }
    ++i;
    while (i < tag.size() && blank(tag[i])) ++i;
    if (i >= tag.size()) break;
    const char quote = tag[i];
    if (quote != '"' && quote != '\'') continue;
    const std::size_t value_start = ++i;
    while (i < tag.size() && tag[i] != quote) ++i;
    if (name == key) return tag.substr(value_start, i - value_start);
    ++i;
  }
  return "";
}

}  // namespace

struct ColladaNodeScan::State {
  enum class Mode { text, open, bang, bang_dash, tag, comment, cdata, instruction, declaration };
  Mode mode = Mode::text;
  char quote = 0, last = 0, before_last = 0;
  int brackets = 0;
  std::string tag;        // the start or end tag's text after '<', at most kMaxTagBytes
  char tag_last = 0;      // its last byte (tag may be cut)

  // A <node>, or a <visual_scene> (the root assimp builds the scene from).
  struct Node {
    std::string id, name;                 // "" when the attribute is absent (assimp matches "" then)
    bool library_top = false;             // directly inside <library_nodes>: assimp's node library
    bool scene_tree = false;              // a visual scene or a node inside one
    std::vector<std::size_t> children;    // nested <node>s
    std::vector<std::string> references;  // <instance_node> urls without '#'
  };
  std::vector<Node> nodes;
  std::vector<std::size_t> roots;
  // Per open element: the node it is (or npos) and whether it is a <visual_scene>.
  struct Open {
    std::size_t node;
    bool visual_scene;
    bool index_list;
    std::size_t accessor;  // index in `accessors`, or npos
    bool primitive;        // the innermost of open_primitives
  };

  void end_primitive() {
    const Primitive p = open_primitives.back();
    open_primitives.pop_back();
    const bool polygons = p.element == "polygons";
    if (!primitive_problem.empty() || (polygons ? p.lists == p.count : (p.count == 0 || p.lists == 1))) return;
    primitive_problem = "<" + p.element + " count=\"" + std::to_string(p.count) + "\"> holds " +
                        std::to_string(p.lists) + " <p> lists, not " +
                        (polygons ? std::to_string(p.count) + " (one per polygon)" : std::string("1")) +
                        " (assimp asserts they match and aborts)";
    primitive_problem_at = p.at;
  }
  std::vector<Open> open;
  std::vector<std::size_t> open_nodes;
  int visual_scenes = 0;  // open <visual_scene> elements

  // Index lists (<p>, <vcount>, <v>, <h>): open ones, the first byte assimp's
  // number loop would stall on, and the largest sum of one <vcount>'s numbers.
  int open_index_lists = 0;
  std::uint64_t offset = 0;  // bytes fed so far
  std::uint64_t stall_at = 0;
  std::string stall_element;
  char stall_byte = 0;
  std::string index_element;     // the innermost open index list's name
  std::uint64_t vcount_sum = 0, vcount_number = 0, max_vcount_sum = 0;
  bool in_vcount = false;
  // Float arrays by id (their `count`: assimp reads that many values or
  // fails), string arrays, and accessors: what they read from which array.
  std::unordered_map<std::string, std::uint64_t> float_arrays;
  std::unordered_map<std::string, bool> string_arrays;
  struct Accessor {
    std::string source;
    std::uint64_t count, offset, stride, params = 0, at;
  };
  std::vector<Accessor> accessors;
  // Primitive elements whose count assimp asserts against the <p> lists read
  // (triangles, polylist: one <p> when count > 0; polygons: one per polygon).
  struct Primitive {
    std::string element;
    std::uint64_t count, lists = 0, at;
  };
  std::vector<Primitive> open_primitives;
  std::string primitive_problem;
  std::uint64_t primitive_problem_at = 0;
  // The largest `count` attribute of an array, primitive or accessor.
  std::uint64_t max_count = 0, max_count_at = 0;
  std::string max_count_element;

  void add_tag_byte(char c) {
    if (tag.size() < kMaxTagBytes) tag += c;
    tag_last = c;
  }

  void end_of_tag() {
    if (!tag.empty() && tag[0] == '/') {  // an end tag
      if (!open.empty()) {
        if (open.back().node != std::string::npos) open_nodes.pop_back();
        if (open.back().visual_scene) --visual_scenes;
        if (open.back().index_list) --open_index_lists;
        if (open.back().primitive) end_primitive();
        if (in_vcount && open.back().index_list) {
          end_vcount_number();
          max_vcount_sum = std::max(max_vcount_sum, vcount_sum);
          in_vcount = false;
        }
        open.pop_back();
      }
      return;
    }
    std::size_t end = 0;
    while (end < tag.size() && !blank(tag[end]) && tag[end] != '/') ++end;
    std::string element = tag.substr(0, end);
    if (const std::size_t colon = element.find(':'); colon != std::string::npos) element.erase(0, colon + 1);
    const bool self_closing = tag_last == '/';
    if (counted_element(element)) {
      const std::uint64_t count = number(attribute(tag, end, "count"));
      if (count > max_count) max_count = count, max_count_at = offset, max_count_element = element;
    }
    const bool index_list = element == "p" || element == "vcount" || element == "v" || element == "h";
    if (element == "float_array") {
      float_arrays.emplace(attribute(tag, end, "id"), number(attribute(tag, end, "count")));
    } else if (element == "Name_array" || element == "IDREF_array") {
      string_arrays.emplace(attribute(tag, end, "id"), true);
    } else if (element == "param" && !open.empty() && open.back().accessor != std::string::npos) {
      ++accessors[open.back().accessor].params;
    }
    if (element == "p" && !open.empty() && open.back().primitive) ++open_primitives.back().lists;
    const bool primitive = element == "triangles" || element == "polylist" || element == "polygons";
    if (primitive && !self_closing) open_primitives.push_back({element, number(attribute(tag, end, "count")), 0, offset});
    std::size_t accessor = std::string::npos;
    if (element == "accessor") {
      std::string source = attribute(tag, end, "source");
      if (!source.empty() && source[0] == '#') source.erase(0, 1);
      const std::string stride = attribute(tag, end, "stride");
      accessor = accessors.size();
      accessors.push_back({source, number(attribute(tag, end, "count")), number(attribute(tag, end, "offset")),
                           stride.empty() ? 1 : number(stride), 0, offset});
    }
    std::size_t node = std::string::npos;
    if (element == "node" || element == "visual_scene") {
      node = nodes.size();
      Node n;
      n.id = attribute(tag, end, "id");
      n.name = attribute(tag, end, "name");
      n.scene_tree = visual_scenes > 0 || element == "visual_scene";
      n.library_top = element == "node" && open_nodes.empty() && visual_scenes == 0;
      nodes.push_back(std::move(n));
      if (element == "visual_scene")
        roots.push_back(node);
      else if (!open_nodes.empty())
        nodes[open_nodes.back()].children.push_back(node);
    } else if (element == "instance_node" && !open_nodes.empty()) {
      std::string url = attribute(tag, end, "url");
      if (!url.empty() && url[0] == '#') nodes[open_nodes.back()].references.push_back(url.substr(1));
    }
    if (self_closing) return;
    const bool visual_scene = element == "visual_scene";
    open.push_back({node, visual_scene, index_list, accessor, primitive});
    if (node != std::string::npos) open_nodes.push_back(node);
    if (visual_scene) ++visual_scenes;
    if (index_list) {
      ++open_index_lists;
      index_element = element;
      if (element == "vcount") in_vcount = true, vcount_sum = 0, vcount_number = 0;
    }
  }

  // A text byte: inside an index list, assimp reads numbers (an optional sign
  // and digits) separated by blanks and loops for ever on anything else.
  void text_byte(char c) {
    if (open_index_lists == 0 || open.empty() || !open.back().index_list) return;
    const bool digit = c >= '0' && c <= '9';
    if (!digit && c != '+' && c != '-' && !blank(c) && c != '\f' && stall_element.empty())
      stall_at = offset, stall_element = index_element, stall_byte = c;
    if (!in_vcount) return;
    if (digit)
      vcount_number = std::min<std::uint64_t>(vcount_number * 10 + std::uint64_t(c - '0'), std::uint64_t{1} << 40);
    else
      end_vcount_number();
  }
  void end_vcount_number() {
    vcount_sum = saturating_add(vcount_sum, vcount_number);
    vcount_number = 0;
  }

  void byte(char c) {
    switch (mode) {
      case Mode::text:
        if (c == '<')
          mode = Mode::open;
        else
          text_byte(c);
        break;
      case Mode::open:
        if (c == '?') {
          mode = Mode::instruction;
        } else if (c == '!') {
          mode = Mode::bang;
        } else {
          mode = Mode::tag, quote = 0, tag.clear(), tag_last = 0;
          tag_byte(c);
        }
        break;
      case Mode::bang:  // "<!--" comment, "<![CDATA[" section, else a declaration
        if (c == '-') {
          mode = Mode::bang_dash;
        } else if (c == '[') {
          mode = Mode::cdata, last = before_last = 0;
          return;
        } else {
          mode = Mode::declaration, quote = 0, brackets = 0;
          declaration_byte(c);
        }
        break;
      case Mode::bang_dash:
        if (c == '-') {
          mode = Mode::comment, last = before_last = 0;
          return;
        }
        mode = Mode::declaration, quote = 0, brackets = 0;
        declaration_byte(c);
        break;
      case Mode::comment:
        if (c == '>' && last == '-' && before_last == '-') mode = Mode::text;
        break;
      case Mode::cdata:
        if (c == '>' && last == ']' && before_last == ']') mode = Mode::text;
        break;
      case Mode::instruction:
        if (c == '>' && last == '?') mode = Mode::text;
        break;
      case Mode::declaration:
        declaration_byte(c);
        break;
      case Mode::tag:
        tag_byte(c);
        break;
    }
    before_last = last;
    last = c;
  }

  void tag_byte(char c) {
    if (quote) {
      if (c == quote) quote = 0;
      add_tag_byte(c);
    } else if (c == '"' || c == '\'') {
      quote = c;
      add_tag_byte(c);
    } else if (c == '>') {
      end_of_tag();
      mode = Mode::text;
    } else {
      add_tag_byte(c);
    }
  }

  void declaration_byte(char c) {
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '[') {
      ++brackets;
    } else if (c == ']') {
      if (brackets > 0) --brackets;
    } else if (c == '>' && brackets == 0) {
      mode = Mode::text;
    }
  }
};

ColladaNodeScan::ColladaNodeScan() : state_(std::make_unique<State>()) {}
ColladaNodeScan::~ColladaNodeScan() = default;

void ColladaNodeScan::feed(const char* data, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i, ++state_->offset) state_->byte(data[i]);
}

void ColladaNodeScan::check_lists(const std::string& name) const {
  const State& s = *state_;
  if (!s.stall_element.empty()) {
    const auto u = static_cast<unsigned char>(s.stall_byte);
    const std::string shown = u >= 0x21 && u < 0x7F ? "'" + std::string(1, s.stall_byte) + "'"
                                                    : "byte " + std::to_string(u);
    throw InputError(name, at_byte(s.stall_at),
                     "<" + s.stall_element + "> holds " + shown +
                         ", not an index (only digits, signs and blanks; assimp's reader would loop for ever)");
  }
  if (s.max_count > s.offset)
    throw InputError(name, at_byte(s.max_count_at),
                     "<" + s.max_count_element + " count=\"" + std::to_string(s.max_count) +
                         "\">: more than the file's " + std::to_string(s.offset) + " bytes can hold");
  if (!s.primitive_problem.empty()) throw InputError(name, at_byte(s.primitive_problem_at), s.primitive_problem);
  for (const State::Accessor& a : s.accessors) {
    const auto array = s.float_arrays.find(a.source);
    if (array == s.float_arrays.end()) continue;  // a string array, another document, or none: assimp's to say
    const std::string accessor = "<accessor source=\"#" + a.source + "\">";
    if (a.params > a.stride)
      throw InputError(name, at_byte(a.at),
                       accessor + " has " + std::to_string(a.params) + " params but a stride of " +
                           std::to_string(a.stride) + " (assimp would read past each element)");
    const std::uint64_t reach = saturating_add(a.offset, a.count > 0 && a.stride > (std::uint64_t{1} << 62) / a.count
                                                             ? std::numeric_limits<std::uint64_t>::max()
                                                             : a.count * a.stride);
    if (reach > array->second)
      throw InputError(name, at_byte(a.at),
                       accessor + " reads " + std::to_string(a.count) + " elements of stride " +
                           std::to_string(a.stride) + " from offset " + std::to_string(a.offset) +
                           ", past the " + std::to_string(array->second) +
                           " values of its float_array (assimp does not check and would read beyond it)");
  }
  if (s.max_vcount_sum > s.offset)
    throw InputError(name, "",
                     "a <vcount> sums to " + std::to_string(s.max_vcount_sum) + " corners, more than the file's " +
                         std::to_string(s.offset) + " bytes can hold");
}

ColladaNodeGraph ColladaNodeScan::measure(const std::string& name) const {
  const auto& nodes = state_->nodes;
  const std::size_t n = nodes.size();
  // Where assimp looks a reference up: its node library (the nodes directly
  // inside <library_nodes>, by id), else the scene's tree by name or id. A
  // reference counts every node it could resolve to (ids need not be unique,
  // nor is it told here which visual scene is the scene's), "" included.
  std::unordered_map<std::string, std::vector<std::size_t>> library, scene;
  for (std::size_t i = 0; i < n; ++i) {
    if (nodes[i].library_top) library[nodes[i].id].push_back(i);
    if (nodes[i].scene_tree) {
      scene[nodes[i].id].push_back(i);
      if (nodes[i].name != nodes[i].id) scene[nodes[i].name].push_back(i);
    }
  }
  // Every node's successors: nested nodes, then the nodes it instances.
  std::vector<std::vector<std::size_t>> next(n);
  for (std::size_t i = 0; i < n; ++i) {
    next[i] = nodes[i].children;
    for (const std::string& url : nodes[i].references) {
      const std::vector<std::size_t>* targets = nullptr;
      if (const auto in_library = library.find(url); in_library != library.end())
        targets = &in_library->second;
      else if (const auto in_scene = scene.find(url); in_scene != scene.end())
        targets = &in_scene->second;
      if (targets) next[i].insert(next[i].end(), targets->begin(), targets->end());
    }
  }
  // Post order over the graph (iterative: a chain of references may be long), each node once.
  enum : char { unseen, open, done };
  std::vector<char> state(n, unseen);
  std::vector<int> depth(n, 0);
  std::vector<std::uint64_t> copies(n, 0);
  std::vector<std::pair<std::size_t, std::size_t>> stack;  // node, next successor
  ColladaNodeGraph graph;
  for (const std::size_t root : state_->roots) {
    if (state[root] == unseen) {
      stack.push_back({root, 0});
      state[root] = open;
    }
    while (!stack.empty()) {
      auto& [node, at] = stack.back();
      if (at < next[node].size()) {
        const std::size_t child = next[node][at++];
        if (state[child] == open) {
          const std::string& label = nodes[child].id.empty() ? nodes[child].name : nodes[child].id;
          throw InputError(name, "node '" + label + "'", "is its own ancestor (a cycle through instance_node)");
        }
        if (state[child] == unseen) {
          state[child] = open;
          stack.push_back({child, 0});
        }
        continue;
      }
      int d = 0;
      std::uint64_t c = 1;
      for (const std::size_t child : next[node]) {
        d = std::max(d, depth[child]);
        c = saturating_add(c, copies[child]);
      }
      depth[node] = d == std::numeric_limits<int>::max() ? d : d + 1;
      copies[node] = c;
      state[node] = done;
      stack.pop_back();
    }
    graph.depth = std::max(graph.depth, depth[root]);
    graph.node_instances = saturating_add(graph.node_instances, copies[root]);
  }
  return graph;
}

namespace {

void refuse_beyond_limits(const std::string& name, const ColladaNodeGraph& graph) {
  if (graph.depth > kMaxColladaNodeDepth)
    throw InputError(name, "",
                     "node hierarchy " + std::to_string(graph.depth) + " levels deep (instance_node included), more than " +
                         std::to_string(kMaxColladaNodeDepth));
  if (graph.node_instances > kMaxColladaNodeInstances)
    throw InputError(name, "",
                     "node graph places " +
                         (graph.node_instances == std::numeric_limits<std::uint64_t>::max()
                              ? std::string("more than 2^64")
                              : std::to_string(graph.node_instances)) +
                         " node instances (a node placed by several instance_node references is copied per "
                         "path), more than " +
                         std::to_string(kMaxColladaNodeInstances));
}

}  // namespace

void check_collada_node_graph(const std::string& name, const char* data, std::size_t size) {
  ColladaNodeScan scan;
  scan.feed(data, size);
  scan.check_lists(name);
  refuse_beyond_limits(name, scan.measure(name));
}

void check_collada_node_graph_of_file(const std::string& name, const std::filesystem::path& file) {
  ColladaNodeScan scan;
  BufferedInput in(file);
  while (in.fetch(1)) {
    const std::size_t n = in.buffered();
    scan.feed(in.fetch(n), n);
    in.consume(n);
  }
  scan.check_lists(name);
  refuse_beyond_limits(name, scan.measure(name));
}

}  // namespace cellbake
