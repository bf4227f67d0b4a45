#include "core/config.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include "core/utf8.h"

namespace cgsr::config {

struct Document::Data {
  std::string origin = "<defaults>";
  YAML::Node root = YAML::Node(YAML::NodeType::Map);
  // Nodes written by --set, with the assignment that wrote them.
  std::vector<std::pair<YAML::Node, std::string>> overrides;
};

Document::Document() : data_(std::make_shared<Data>()) {}

namespace {
// Bounds of a config, checked before (bytes) and right after (the rest) yaml-cpp reads it, before
// any schema walks it: the largest config in configs/ is a few KiB, and a 10 MB list took 1.7 GB.
constexpr size_t kMaxConfigBytes = size_t{1} << 20;
constexpr size_t kMaxListItems = 100000;
constexpr size_t kMaxValues = 1000000;  // every node counted, aliases as often as they are used
constexpr int kMaxDepth = 64;

std::string mark_text(const std::string& origin, const YAML::Mark& mark) {
  if (mark.is_null()) return origin;
  return origin + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

void check_size(size_t bytes, const std::string& origin) {
  if (bytes > kMaxConfigBytes)
    throw Error(origin, "the config is " + std::to_string(bytes) + " bytes, more than the limit of " +
                            std::to_string(kMaxConfigBytes) + " (1 MiB)");
}

// Duplicate keys (yaml-cpp keeps both and reads the first), and lists, values and nesting beyond
// the bounds above.
void check_structure(const YAML::Node& node, const std::string& origin, int depth, size_t& values) {
  if (++values > kMaxValues)
    throw Error(mark_text(origin, node.Mark()), "more than " + std::to_string(kMaxValues) +
                                                    " values (counting each use of an alias)");
  if (depth > kMaxDepth)
    throw Error(mark_text(origin, node.Mark()), "nested deeper than " + std::to_string(kMaxDepth) + " levels");
  if (node.IsSequence()) {
    if (node.size() > kMaxListItems)
      throw Error(mark_text(origin, node.Mark()), "a list of " + std::to_string(node.size()) +
                                                      " items, more than the limit of " + std::to_string(kMaxListItems));
    for (const auto& item : node) check_structure(item, origin, depth + 1, values);
  } else if (node.IsMap()) {
    std::map<std::string, YAML::Mark> seen;
    for (const auto& kv : node) {
      if (kv.first.IsScalar()) {
        const auto [first, inserted] = seen.emplace(kv.first.Scalar(), kv.first.Mark());
        if (!inserted)
          throw Error(mark_text(origin, kv.first.Mark()),
                      "duplicate key '" + kv.first.Scalar() + "' (first at line " +
                          std::to_string(first->second.line + 1) + "); keep one");
      }
      check_structure(kv.second, origin, depth + 1, values);
    }
  }
}

// Config values reach JSON files (results.json, manifests, model files), which must be UTF-8.
void check_utf8(const std::string& text, const std::string& origin) {
  const auto bad = first_invalid_utf8(text);
  if (!bad) return;
  const size_t newline = *bad == 0 ? std::string::npos : text.rfind('\n', *bad - 1);
  const size_t line_start = newline == std::string::npos ? 0 : newline + 1;
  const size_t line = 1 + static_cast<size_t>(std::count(text.begin(), text.begin() + static_cast<long>(*bad), '\n'));
  const size_t column = *bad - line_start + 1;
  char hex[8];
  std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned char>(text[*bad]));
  throw Error(origin + ":" + std::to_string(line) + ":" + std::to_string(column),
              std::string("not valid UTF-8 (byte ") + hex + "); config values are written to JSON files, which must be UTF-8");
}

YAML::Node load_checked(const std::string& text, const std::string& origin) {
  check_size(text.size(), origin);
  check_utf8(text, origin);
  YAML::Node root = YAML::Load(text);
  size_t values = 0;
  check_structure(root, origin, 0, values);
  return root;
}
}  // namespace

Document Document::load_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) {
    throw Error(path.string(), std::filesystem::exists(path) ? "cannot read the file" : "no such config file");
  }
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  if (!ec) check_size(bytes, path.string());  // before reading it
  std::stringstream text;
  text << in.rdbuf();
  return parse(text.str(), path.string());
}

Document Document::parse(const std::string& text, const std::string& origin) {
  Document doc;
  doc.data_->origin = origin;
  try {
    YAML::Node root = load_checked(text, origin);
    if (root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
    doc.data_->root = root;
  } catch (const YAML::Exception& e) {
    throw Error(origin + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1),
                "invalid YAML: " + e.msg);
  }
  if (!doc.data_->root.IsMap()) throw Error(origin, "the top level must be a map of keys");
  return doc;
}

void Document::apply_override(const std::string& assignment, const std::string& origin) {
  const size_t eq = assignment.find('=');
  const std::string where = origin.empty() ? "--set " + assignment : origin;
  if (eq == std::string::npos || eq == 0) throw Error(where, "expected key.path=value");
  const auto keys = split(assignment.substr(0, eq), '.');
  for (const auto& k : keys)
    if (k.empty()) throw Error(where, "empty key in the key path");

  YAML::Node value;
  try {
    value = load_checked(assignment.substr(eq + 1), where);
  } catch (const YAML::Exception& e) {
    throw Error(where, "the value is not valid YAML: " + e.msg);
  }

  // Walk down, creating maps as needed. yaml-cpp's operator[] on a Node returns a view that
  // must be reassigned, so keep the chain explicit.
  std::vector<YAML::Node> chain{data_->root};
  for (size_t i = 0; i + 1 < keys.size(); ++i) {
    YAML::Node next = chain.back()[keys[i]];
    if (!next || next.IsNull()) {
      chain.back()[keys[i]] = YAML::Node(YAML::NodeType::Map);
      next = chain.back()[keys[i]];
      // A map made for the path has no file position: errors about it name the assignment.
      data_->overrides.emplace_back(next, where);
    } else if (!next.IsMap()) {
      throw Error(where, "'" + keys[i] + "' is not a map, so it has no key '" + keys[i + 1] + "'");
    }
    chain.push_back(next);
  }
  chain.back()[keys.back()] = value;
  data_->overrides.emplace_back(chain.back()[keys.back()], where);
  // Every node inside the value too: an error about a list element or an inner key names the
  // assignment, not the config file's position of the same line and column.
  std::function<void(const YAML::Node&)> record_inner = [&](const YAML::Node& node) {
    if (node.IsSequence()) {
      for (const auto& item : node) {
        data_->overrides.emplace_back(item, where);
        record_inner(item);
      }
    } else if (node.IsMap()) {
      for (const auto& kv : node) {
        data_->overrides.emplace_back(kv.first, where);
        data_->overrides.emplace_back(kv.second, where);
        record_inner(kv.second);
      }
    }
  };
  record_inner(value);
}

const YAML::Node& Document::root() const { return data_->root; }
const std::string& Document::origin() const { return data_->origin; }

std::string Document::locate(const YAML::Node& node) const {
  for (const auto& [written, where] : data_->overrides)
    if (written.is(node)) return where;
  if (!node.IsDefined()) return data_->origin;
  const YAML::Mark mark = node.Mark();
  if (mark.is_null()) return data_->origin;
  return data_->origin + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

bool Document::is_override(const YAML::Node& node) const {
  for (const auto& entry : data_->overrides)
    if (entry.first.is(node)) return true;
  return false;
}

void Cursor::fail(const YAML::Node& node, const std::string& what) const {
  const std::string where = doc ? doc->locate(node) : std::string();
  throw Error(where, path.empty() ? what : path + ": " + what);
}

namespace detail {
std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing (null)";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a map";
  return "'" + node.Scalar() + "'";
}

std::string number(double x) {
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  std::ostringstream out;
  out.precision(12);
  out << x;
  return out.str();
}

void require_in_range(double v, double lo, double hi, const YAML::Node& node, const Cursor& at) {
  if (v >= lo && v <= hi) return;
  at.fail(node, node.IsScalar() ? out_of_range(node.Scalar(), lo, hi) : out_of_range(v, lo, hi));
}

void check_range(const YAML::Node& node, double lo, double hi, const Cursor& at) {
  if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) check_range(node[i], lo, hi, at.index(i));
    return;
  }
  double x = 0;
  // Not a finite number: the field's decoder says what was expected.
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, x) || !std::isfinite(x)) return;
  require_in_range(x, lo, hi, node, at);
}

YAML::Node lift_moved_blocks(const YAML::Node& map, const std::vector<std::string>& moved, const Cursor& at) {
  if (!map || !map.IsMap()) return map;
  const auto is_moved = [&](const YAML::Node& key) {
    return key.IsScalar() && std::find(moved.begin(), moved.end(), key.Scalar()) != moved.end();
  };
  bool any = false;
  for (const auto& kv : map) any = any || is_moved(kv.first);
  if (!any) return map;

  YAML::Node out(YAML::NodeType::Map);
  for (const auto& kv : map) {
    if (!is_moved(kv.first)) {
      out.force_insert(kv.first, kv.second);
      continue;
    }
    const Cursor old = at.child(kv.first.Scalar());
    if (!kv.second.IsMap()) old.fail(kv.second, "expected a map of keys, got " + describe(kv.second));
    const std::string where = at.doc ? at.doc->locate(kv.first) : old.path;
    const std::string here = at.path.empty() ? "the top level" : "'" + at.path + "'";
    std::string example = "<key>";
    for (const auto& inner : kv.second)
      if (inner.first.IsScalar()) {
        example = inner.first.Scalar();
        break;
      }
    warn_deprecated(where, "'" + old.path + "' is deprecated: write its keys directly at " + here + " ('" +
                               at.child(example).path + "' instead of '" + old.child(example).path + "')");
    for (const auto& inner : kv.second) {
      if (inner.first.IsScalar() && map[inner.first.Scalar()])
        old.child(inner.first.Scalar())
            .fail(inner.first, "is also given as '" + at.child(inner.first.Scalar()).path + "'; keep one");
      out.force_insert(inner.first, inner.second);
    }
  }
  return out;
}
}  // namespace detail

std::string out_of_range(const std::string& written, double lo, double hi) {
  return "'" + written + "' is out of range [" + detail::number(lo) + ", " + detail::number(hi) +
         (std::isinf(hi) ? ")" : "]");
}

std::string out_of_range(double value, double lo, double hi) { return out_of_range(detail::number(value), lo, hi); }

std::string block_type(const Block& block) {
  const Cursor at = block.cursor();
  if (!block.node.IsMap()) at.fail(block.node, "expected a block {type: Name, ...}, got " + detail::describe(block.node));
  const YAML::Node type = block.node["type"];
  if (!type) at.fail(block.node, "missing required key 'type'");
  return Codec<std::string>::decode(type, at.child("type"));
}

void warn_deprecated(const std::string& where, const std::string& what) {
  static std::mutex mutex;
  static std::set<std::string> warned;
  const std::lock_guard lock(mutex);
  const std::string message = where + ": " + what;
  if (warned.count(message)) return;
  if (warned.size() < 1000) warned.insert(message);  // bounded: a long-lived process parses many configs
  spdlog::warn("{}", message);
}

std::string to_yaml(const YAML::Node& node) {
  YAML::Emitter out;
  out << node;
  return std::string(out.c_str()) + "\n";
}

}  // namespace cgsr::config
