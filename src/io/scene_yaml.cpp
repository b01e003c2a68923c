// Duplicate-key pre-scan of scene YAML, the wrapped Teuchos parse, and the
// parse of one --set value (see scene_yaml.hpp).
#include "io/scene_yaml.hpp"

#include <Teuchos_YamlParameterListHelpers.hpp>
#include <algorithm>
#include <map>
#include <regex>
#include <stdexcept>
#include <vector>

namespace bfemp {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && is_space(s[a])) ++a;
  while (b > a && is_space(s[b - 1])) --b;
  return s.substr(a, b - a);
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  for (std::size_t a = 0; a <= text.size();) {
    const std::size_t b = std::min(text.find('\n', a), text.size());
    lines.push_back(text.substr(a, b - a));
    a = b + 1;
  }
  return lines;
}

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "/" + key;
}

// Reads the quoted scalar opening at s[i] into out; i ends past the closing
// quote. False when it is not closed.
bool read_quoted(const std::string& s, std::size_t& i, std::string& out) {
  const char q = s[i++];
  out.clear();
  while (i < s.size()) {
    const char c = s[i];
    if (q == '\'' && c == '\'') {
      if (i + 1 < s.size() && s[i + 1] == '\'') {
        out += '\'';
        i += 2;
        continue;
      }
      ++i;
      return true;
    }
    if (q == '"' && c == '\\' && i + 1 < s.size()) {
      out += s[i + 1];
      i += 2;
      continue;
    }
    if (q == '"' && c == '"') {
      ++i;
      return true;
    }
    out += c;
    ++i;
  }
  return false;
}

// Where a comment starts in a value (a '#' after white space, outside quoted
// scalars), or npos. A quote opens a scalar only where a scalar starts.
std::size_t comment_start(const std::string& s) {
  bool scalar_start = true;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (c == '#' && (i == 0 || is_space(s[i - 1]))) return i;
    if (scalar_start && (c == '\'' || c == '"')) {
      std::string skip;
      if (!read_quoted(s, i, skip)) return std::string::npos;
      --i;
      scalar_start = false;
      continue;
    }
    if (c == '{' || c == '[' || c == ',') scalar_start = true;
    else if (c == ':' && (i + 1 == s.size() || is_space(s[i + 1]))) scalar_start = true;
    else if (!is_space(c)) scalar_start = false;
  }
  return std::string::npos;
}

// Reports the first duplicate: the text of a block or flow collection with the
// line of its first character.
struct Reporter {
  std::string label;
  [[noreturn]] void duplicate(const std::string& path, int line, int first) const {
    throw std::invalid_argument(label + " line " + std::to_string(line) + ": key '" + path +
                                "' appears twice (first at line " + std::to_string(first) +
                                "); a YAML map holds each key once");
  }
};

// Scans a flow collection ({...} or [...]) opening at s[i]; returns the index
// past its end (s.size() when unterminated: the parser reports that).
// line0 is the line of s[0].
std::size_t scan_flow(const std::string& s, std::size_t i, const std::string& path, int line0,
                      const Reporter& rep, int depth = 0) {
  if (depth > 256)  // recursion bound: a scene never nests this deep
    throw std::invalid_argument(rep.label + " line " + std::to_string(line0) + ": key '" + path +
                                "': flow collections nested deeper than 256 levels");
  auto line_at = [&](std::size_t pos) {
    int l = line0;
    for (std::size_t k = 0; k < pos && k < s.size(); ++k) l += s[k] == '\n';
    return l;
  };
  // A flow scalar (quoted, or plain up to , ] } or ': ').
  auto scalar = [&](std::size_t& j) {
    std::string out;
    if (s[j] == '\'' || s[j] == '"') {
      if (!read_quoted(s, j, out)) j = s.size();
      return out;
    }
    const std::size_t a = j;
    while (j < s.size()) {
      const char c = s[j];
      if (c == ',' || c == ']' || c == '}') break;
      if (c == ':' && (j + 1 == s.size() || is_space(s[j + 1]) || s[j + 1] == ',' || s[j + 1] == '}' ||
                       s[j + 1] == ']'))
        break;
      ++j;
    }
    return trim(s.substr(a, j - a));
  };
  auto skip_ws = [&](std::size_t& j) {
    while (j < s.size() && is_space(s[j])) ++j;
  };
  const char open = s[i], close = open == '{' ? '}' : ']';
  ++i;
  std::map<std::string, int> seen;
  int item = 0;
  while (true) {
    skip_ws(i);
    if (i >= s.size()) return s.size();
    if (s[i] == close) return i + 1;
    if (s[i] == ',') {
      ++i;
      continue;
    }
    if (s[i] == '}' || s[i] == ']') return i + 1;  // mismatched: the parser reports it
    const std::size_t start = i;
    std::string key;
    if (s[i] == '{' || s[i] == '[') {
      i = scan_flow(s, i, path + "[" + std::to_string(item) + "]", line_at(i), rep, depth + 1);
    } else {
      key = scalar(i);
    }
    skip_ws(i);
    if (i < s.size() && s[i] == ':') {
      ++i;
      if (open == '{') {
        const int line = line_at(start);
        const auto [it, fresh] = seen.emplace(key, line);
        if (!fresh) rep.duplicate(join(path, key), line, it->second);
      }
      skip_ws(i);
      if (i < s.size() && (s[i] == '{' || s[i] == '[')) i = scan_flow(s, i, join(path, key), line_at(i), rep, depth + 1);
      else if (i < s.size() && s[i] != ',' && s[i] != close) scalar(i);
    }
    if (i == start) ++i;  // no progress on a stray character
    ++item;
  }
}

// Brackets still open at the end of s (ignoring quoted scalars); 0 when the
// flow collection is complete.
int open_brackets(const std::string& s) {
  int depth = 0;
  bool scalar_start = true;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (scalar_start && (c == '\'' || c == '"')) {
      std::string skip;
      if (!read_quoted(s, i, skip)) return depth + 1;
      --i;
      scalar_start = false;
      continue;
    }
    if (c == '{' || c == '[') ++depth;
    if (c == '}' || c == ']') --depth;
    scalar_start = c == '{' || c == '[' || c == ',' || (c == ':' && (i + 1 == s.size() || is_space(s[i + 1])));
    if (is_space(c)) scalar_start = scalar_start || (i > 0 && (s[i - 1] == ',' || s[i - 1] == ':'));
  }
  return depth;
}

// The key of a block-mapping line ("key: value", "'a: b': value"); false
// when the line holds no key.
bool block_key(const std::string& c, std::string& key, std::string& value) {
  std::size_t i = 0;
  if (c.empty() || c[0] == '{' || c[0] == '[' || c[0] == '#' || c[0] == '|' || c[0] == '>') return false;
  if (c[0] == '\'' || c[0] == '"') {
    if (!read_quoted(c, i, key)) return false;
    while (i < c.size() && (c[i] == ' ' || c[i] == '\t')) ++i;
    if (i >= c.size() || c[i] != ':' || (i + 1 < c.size() && !is_space(c[i + 1]))) return false;
    ++i;
  } else {
    for (; i < c.size(); ++i) {
      if (c[i] == '#' && i > 0 && is_space(c[i - 1])) return false;
      if (c[i] == ':' && (i + 1 == c.size() || is_space(c[i + 1]))) break;
    }
    if (i == c.size()) return false;
    key = trim(c.substr(0, i));
    ++i;
  }
  value = c.substr(i);
  value = trim(value.substr(0, comment_start(value)));
  return true;
}

// The user's part of a Teuchos parser message: the line and column it names
// (with that line of the scene), and the text without source paths, throw
// counters, parser states and lexer dumps.
std::string parser_message(const std::string& what, const std::string& yaml) {
  const std::vector<std::string> in = split_lines(what);
  static const std::regex at("line ([0-9]+) column ([0-9]+)");
  static const std::regex source_path("^.*\\.(cpp|hpp|h):[0-9]+:\\s*$");
  static const std::regex exists("Parameter \"(.*)\" already exists in list .*");
  std::string where;
  std::vector<std::string> kept;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const std::string t = trim(in[i]);
    std::smatch m;
    if (t.rfind("error: ", 0) == 0 && std::regex_search(t, m, at)) {
      const std::size_t line = std::stoul(m[1]);
      where = " line " + std::string(m[1]) + ", column " + std::string(m[2]);
      const std::vector<std::string> src = split_lines(yaml);  // quote that line of the scene
      if (line >= 1 && line <= src.size() && !trim(src[line - 1]).empty())
        where += " ('" + trim(src[line - 1]) + "')";
      continue;
    }
    if (t.empty() || t == "^" || std::regex_match(t, source_path) || t.rfind("Throw number", 0) == 0 ||
        t.rfind("Throw test that evaluated", 0) == 0 || t.rfind("Parser was in state", 0) == 0)
      continue;
    if (i + 1 < in.size() && trim(in[i + 1]) == "^") continue;  // the quoted line above the caret
    if (t.rfind("Lexer text:", 0) == 0) {
      // The lexer's text is quoted and may span lines (a newline): skip to
      // the closing quote.
      if (std::count(t.begin(), t.end(), '"') % 2 == 1)
        while (i + 1 < in.size() && in[++i].find('"') == std::string::npos) {
        }
      continue;
    }
    if (std::regex_match(t, m, exists)) {
      kept.push_back("key '" + std::string(m[1]) + "' appears twice in one map");
      continue;
    }
    if (t == "Got: NEWLINE") kept.push_back("got the end of the line");
    else if (t == "Got: INDENT" || t == "Got: DEDENT") kept.push_back("got an unexpected indentation");
    else if (t.rfind("Expected one of", 0) == 0) kept.push_back("expected one of " + t.substr(16));
    else if (t.rfind("Got: ", 0) == 0) kept.push_back("got '" + t.substr(5) + "'");
    else kept.push_back(t);
  }
  std::string text;
  for (const auto& k : kept)
    if (k != "Error!") text += (text.empty() ? "" : "; ") + k;
  if (text.empty()) text = "the YAML parser could not read it (expected a map 'bfemp:' of keys)";
  return where + ": " + text;
}

// False when every line is blank, a comment, a directive or a document marker.
bool has_content(const std::string& yaml) {
  for (const auto& l : split_lines(yaml)) {
    const std::string t = trim(l);
    if (!t.empty() && t[0] != '#' && t[0] != '%' && t != "---" && t != "...") return true;
  }
  return false;
}

}  // namespace

void check_duplicate_keys(const std::string& yaml, const std::string& label) {
  const Reporter rep{label};
  const std::vector<std::string> lines = split_lines(yaml);
  struct Level {
    int indent;
    std::string path;
    std::map<std::string, int> keys;
    std::string last;  // path of the last key of this mapping
  };
  std::vector<Level> stack;
  std::string last;  // path of the last key anywhere
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const int line_no = static_cast<int>(n) + 1;
    std::string line = lines[n];
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::size_t ind = 0;
    while (ind < line.size() && (line[ind] == ' ' || line[ind] == '\t')) ++ind;
    const std::string content = line.substr(ind);
    if (content.empty() || content[0] == '#') continue;
    if (line[0] == '%' || line.rfind("---", 0) == 0 || line.rfind("...", 0) == 0) {
      stack.clear();  // a directive or a new document
      last.clear();
      continue;
    }
    if (line.substr(0, ind).find('\t') != std::string::npos)
      throw std::invalid_argument(label + " line " + std::to_string(line_no) +
                                  ": a tab in the indentation; YAML indents with spaces only");
    int indent = static_cast<int>(ind);
    std::string body = content;
    bool item = false;
    if (body == "-" || body.rfind("- ", 0) == 0) {  // block sequence item
      std::size_t k = 1;
      while (k < body.size() && body[k] == ' ') ++k;
      while (!stack.empty() && stack.back().indent > indent) stack.pop_back();
      last = stack.empty() ? std::string() : stack.back().last;
      indent += static_cast<int>(k);
      body = body.substr(k);
      item = true;
    }
    std::string key, value;
    if (!block_key(body, key, value)) continue;  // a plain or flow value line
    bool dedent = false;
    while (!stack.empty() && stack.back().indent > indent) {
      stack.pop_back();
      dedent = true;
    }
    if (dedent && !item && (stack.empty() || stack.back().indent != indent))
      throw std::invalid_argument(label + " line " + std::to_string(line_no) + ": key '" + key + "' is indented by " +
                                  std::to_string(indent) +
                                  " spaces, which matches no enclosing map; line it up with its sibling keys");
    if (item && !stack.empty() && stack.back().indent == indent) stack.pop_back();  // a new item's map
    if (stack.empty() || stack.back().indent < indent) stack.push_back(Level{indent, last, {}, ""});
    Level& level = stack.back();
    const std::string path = join(level.path, key);
    const auto [it, fresh] = level.keys.emplace(key, line_no);
    if (!fresh) {
      // The top-level key 'bfemp' is left out of paths, as in every other message.
      const std::string shown = path.rfind("bfemp/", 0) == 0 ? path.substr(6) : path;
      rep.duplicate(shown, line_no, it->second);
    }
    level.last = last = path;
    if (!value.empty() && (value[0] == '{' || value[0] == '[')) {
      std::string flow = value;
      while (open_brackets(flow) > 0 && n + 1 < lines.size()) {
        const std::string next = lines[++n];
        flow += "\n" + next.substr(0, comment_start(next));
      }
      const std::string shown = path.rfind("bfemp/", 0) == 0 ? path.substr(6) : path;
      scan_flow(flow, 0, shown, line_no, rep);
    } else if (!value.empty() && (value[0] == '|' || value[0] == '>')) {
      while (n + 1 < lines.size()) {  // block scalar: the more indented lines
        const std::string& next = lines[n + 1];
        const std::size_t ni = next.find_first_not_of(' ');
        if (ni != std::string::npos && static_cast<int>(ni) <= indent) break;
        ++n;
      }
    }
  }
}

Teuchos::RCP<Teuchos::ParameterList> parse_scene_yaml(const std::string& yaml, const std::string& label) {
  check_duplicate_keys(yaml, label);
  if (!has_content(yaml))
    throw std::invalid_argument(label + " is empty: expected a YAML map with the top-level key 'bfemp'");
  try {
    return Teuchos::getParametersFromYamlString(yaml);
  } catch (const std::exception& e) {
    throw std::invalid_argument(label + parser_message(e.what(), yaml) + " (not valid YAML)");
  }
}

Teuchos::ParameterEntry parse_yaml_value(const std::string& value, const std::string& what) {
  std::string v = trim(value);
  if (v.size() >= 2 && v.front() == '{' && v.back() == '}' && v.find(':') == std::string::npos)
    v = "[" + v.substr(1, v.size() - 2) + "]";  // the older list form {1.0, 0.0}
  if (v.empty()) return Teuchos::ParameterEntry(std::string());
  if (v.size() >= 2 && v.front() == '[' && v.back() == ']' && trim(v.substr(1, v.size() - 2)).empty())
    return Teuchos::ParameterEntry(Teuchos::Array<double>());  // [] (the parser cannot type it)
  if (v.find('\n') != std::string::npos)
    throw std::invalid_argument(what + " = '" + value + "': expected a value on one line");
  const std::string doc = "v:\n  v: " + v + "\n";
  Teuchos::RCP<Teuchos::ParameterList> p;
  try {
    p = Teuchos::getParametersFromYamlString(doc);
  } catch (const std::exception& e) {
    std::string m = parser_message(e.what(), "");
    throw std::invalid_argument(what + " = '" + value + "': not a YAML scalar or [list]" +
                                m.substr(m.find(':')));
  }
  if (!p->isParameter("v"))
    throw std::invalid_argument(what + " = '" + value + "': expected one YAML scalar or [list]");
  return p->getEntry("v");
}

}  // namespace bfemp
