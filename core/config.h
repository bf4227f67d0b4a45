#pragma once
// YAML configuration: documents that remember where every value came from, and typed schemas
// that parse a document into a command's options struct.
//
// Each command declares its options once, as a struct with defaults in code, and a Schema that
// binds YAML keys to the struct's fields:
//
//   struct RenderOptions { std::string scene; int frames = 300; };
//   Schema<RenderOptions> render_schema() {
//     Schema<RenderOptions> s;
//     s.field("scene", &RenderOptions::scene, "scene config file").required();
//     s.field("frames", &RenderOptions::frames, "frames to render").range(1, 100000);
//     return s;
//   }
//
// Parsing rejects unknown keys (suggesting the closest valid one), wrong types, values out of
// range and missing required keys, naming the file, line, column and key path. Emitting gives
// the fully resolved config, which every run directory records.

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "core/enum_names.h"
#include "core/error.h"
#include "core/text.h"

namespace cgsr::config {

// A YAML document plus the origin of each node: a file position, or the --set that wrote it.
class Document {
 public:
  Document();  // an empty map, origin "<defaults>"
  static Document load_file(const std::filesystem::path& path);
  static Document parse(const std::string& text, const std::string& origin);

  // Applies "a.b.c=value"; the value is parsed as YAML (so 3 is an int, [1, 2] a list).
  // `origin` names it in errors (default "--set a.b.c=value").
  void apply_override(const std::string& assignment, const std::string& origin = "");

  const YAML::Node& root() const;
  const std::string& origin() const;

  // "file.yaml:12:5", or "--set a.b=v" for overridden values, or the origin when unknown.
  std::string locate(const YAML::Node& node) const;
  bool is_override(const YAML::Node& node) const;

 private:
  struct Data;
  std::shared_ptr<Data> data_;
};

// Where parsing currently is: the document and the dotted key path.
struct Cursor {
  const Document* doc = nullptr;
  std::string path;  // "" at the root

  Cursor child(const std::string& key) const { return {doc, path.empty() ? key : path + "." + key}; }
  Cursor index(size_t i) const { return {doc, path + "[" + std::to_string(i) + "]"}; }
  // A user error at `node`, e.g. "cfg.yaml:3:9: train.steps: must be at least 1".
  [[noreturn]] void fail(const YAML::Node& node, const std::string& what) const;
};

// A raw block kept for a factory to parse later with its own schema (e.g. {type: Name, ...}).
struct Block {
  YAML::Node node;
  std::shared_ptr<const Document> doc;
  std::string path;
  Cursor cursor() const { return {doc.get(), path}; }
};

// The wording of every range error: "'<value>' is out of range [lo, hi]" ("[lo, inf)" when hi is
// infinite). `written` is the value as the user wrote it; a number is written as short as it reads.
// Range checks of config nodes are Schema::range (detail::require_in_range); other inputs (a model
// spec, a manifest, a scene) use these messages so every range error reads the same.
std::string out_of_range(const std::string& written, double lo, double hi);
std::string out_of_range(double value, double lo, double hi);
inline constexpr double kUnbounded = std::numeric_limits<double>::infinity();  // a range's missing upper end

// ---- value codecs: how a scalar or list field is read from and written to YAML ----------------

template <class V, class Enable = void>
struct Codec;

namespace detail {
std::string describe(const YAML::Node& node);  // "'abc'", "a list", "a map", "null"
std::string number(double x);                   // 3, 0.5, 1e+15: as short as it reads
// "'1e15' is out of range [1, 1000000]" at `node` (or at the first element of a list outside it)
// when the number or any element of the list of numbers at `node` lies outside [lo, hi].
void check_range(const YAML::Node& node, double lo, double hi, const Cursor& at);
// The same for a converted value `v` written at `node`.
void require_in_range(double v, double lo, double hi, const YAML::Node& node, const Cursor& at);
// `map` with the keys of each block named in `moved` lifted to its level (Schema::moved_block),
// warning once per block where it was written.
YAML::Node lift_moved_blocks(const YAML::Node& map, const std::vector<std::string>& moved, const Cursor& at);
template <class V>
V scalar_as(const YAML::Node& node, const Cursor& at, const char* type_name) {
  if (!node.IsScalar()) at.fail(node, std::string("expected ") + type_name + ", got " + describe(node));
  try {
    return node.as<V>();
  } catch (const YAML::Exception&) {
    at.fail(node, std::string("expected ") + type_name + ", got " + describe(node));
  }
}
}  // namespace detail

template <>
struct Codec<bool> {
  static bool decode(const YAML::Node& n, const Cursor& at) { return detail::scalar_as<bool>(n, at, "true or false"); }
  static YAML::Node encode(bool v) { return YAML::Node(v); }
};

template <class V>
struct Codec<V, std::enable_if_t<std::is_integral_v<V> && !std::is_same_v<V, bool>>> {
  static V decode(const YAML::Node& n, const Cursor& at) {
    if (n.IsScalar()) {
      V v{};
      if (YAML::convert<V>::decode(n, v)) return v;
      // A whole number written as 1e3, or one too large for the field, is not a type mistake.
      double x = 0;
      if (YAML::convert<double>::decode(n, x) && std::isfinite(x) && x == std::floor(x)) {
        const double lo = static_cast<double>(std::numeric_limits<V>::lowest());
        const double hi = static_cast<double>(std::numeric_limits<V>::max());
        if (x >= lo && x < hi) return static_cast<V>(x);
        at.fail(n, out_of_range(n.Scalar(), lo, hi));
      }
    }
    return detail::scalar_as<V>(n, at, "an integer");
  }
  static YAML::Node encode(V v) { return YAML::Node(v); }
};

template <class V>
struct Codec<V, std::enable_if_t<std::is_floating_point_v<V>>> {
  static V decode(const YAML::Node& n, const Cursor& at) {
    const V v = detail::scalar_as<V>(n, at, "a number");
    if (!std::isfinite(v)) at.fail(n, "expected a finite number, got " + detail::describe(n));
    return v;
  }
  static YAML::Node encode(V v) { return YAML::Node(v); }
};

// A named enum (core/enum_names.h) is written as its name; an unknown name fails with the valid
// ones and a did-you-mean.
template <class V>
struct Codec<V, std::enable_if_t<is_named_enum<V>::value>> {
  static V decode(const YAML::Node& n, const Cursor& at) {
    const auto name = detail::scalar_as<std::string>(n, at, "a string");
    const auto& names = EnumNames<V>::names();
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) at.fail(n, unknown_enum_name<V>(name));
    return static_cast<V>(it - names.begin());
  }
  static YAML::Node encode(V v) { return YAML::Node(enum_name(v)); }
};

template <>
struct Codec<std::string> {
  static std::string decode(const YAML::Node& n, const Cursor& at) {
    return detail::scalar_as<std::string>(n, at, "a string");
  }
  static YAML::Node encode(const std::string& v) { return YAML::Node(v); }
};

template <class V>
struct Codec<std::vector<V>> {
  static std::vector<V> decode(const YAML::Node& n, const Cursor& at) {
    if (!n.IsSequence()) at.fail(n, "expected a list, got " + detail::describe(n));
    std::vector<V> out;
    for (size_t i = 0; i < n.size(); ++i) out.push_back(Codec<V>::decode(n[i], at.index(i)));
    return out;
  }
  static YAML::Node encode(const std::vector<V>& v) {
    YAML::Node n(YAML::NodeType::Sequence);
    for (const auto& x : v) n.push_back(Codec<V>::encode(x));
    n.SetStyle(YAML::EmitterStyle::Flow);
    return n;
  }
};

// ---- schemas -----------------------------------------------------------------------------------

template <class T>
class Schema {
 public:
  // Builder returned by field(): adds constraints to the field just declared.
  template <class V>
  class FieldBuilder {
   public:
    FieldBuilder(Schema& schema, size_t index) : schema_(schema), index_(index) {}
    FieldBuilder& required() {
      schema_.fields_[index_].required = true;
      return *this;
    }
    // Inclusive range; for lists, every element. Checked on the written number before it is
    // converted, so a value too large for the field's type is out of range, not of a wrong type.
    FieldBuilder& range(double lo, double hi) {
      static_assert(std::is_arithmetic_v<V> || std::is_arithmetic_v<typename ValueOf<V>::type>,
                    "range() needs a numeric field");
      auto& f = schema_.fields_[index_];
      auto previous = f.validate;
      f.validate = [previous, lo, hi](const T& obj, const YAML::Node& node, const Cursor& at, const void* member) {
        if (previous) previous(obj, node, at, member);
        // Again on the value: a spelling the number check does not read (0x10) converts too.
        const auto& v = *static_cast<const V*>(member);
        if constexpr (std::is_arithmetic_v<V>) {
          detail::require_in_range(static_cast<double>(v), lo, hi, node, at);
        } else {
          for (size_t i = 0; i < v.size(); ++i)
            detail::require_in_range(static_cast<double>(v[i]), lo, hi, node.IsSequence() ? node[i] : node,
                                     at.index(i));
        }
      };
      f.bounds = {lo, hi};
      return *this;
    }
    FieldBuilder& at_least(double lo) { return range(lo, kUnbounded); }
    FieldBuilder& one_of(std::vector<std::string> allowed) {
      auto& f = schema_.fields_[index_];
      auto previous = f.validate;
      f.validate = [previous, allowed](const T& obj, const YAML::Node& node, const Cursor& at, const void* member) {
        if (previous) previous(obj, node, at, member);
        const auto& v = *static_cast<const V*>(member);
        check_allowed(v, allowed, node, at);
      };
      f.doc += " (one of: " + join(allowed) + ")";
      return *this;
    }
    FieldBuilder& check(std::function<bool(const V&)> ok, std::string message) {
      auto& f = schema_.fields_[index_];
      auto previous = f.validate;
      f.validate = [previous, ok, message](const T& obj, const YAML::Node& node, const Cursor& at, const void* member) {
        if (previous) previous(obj, node, at, member);
        if (!ok(*static_cast<const V*>(member))) at.fail(node, message);
      };
      return *this;
    }

   private:
    template <class X>
    struct ValueOf {
      using type = X;
    };
    template <class X>
    struct ValueOf<std::vector<X>> {
      using type = X;
    };
    template <class X>
    static void check_allowed(const X& v, const std::vector<std::string>& allowed, const YAML::Node& node,
                              const Cursor& at) {
      if constexpr (std::is_same_v<X, std::string>) {
        if (std::find(allowed.begin(), allowed.end(), v) == allowed.end())
          at.fail(node, "'" + v + "' is not one of: " + join(allowed) + did_you_mean(v, allowed));
      } else if constexpr (std::is_same_v<X, std::vector<std::string>>) {
        for (const auto& x : v) check_allowed(x, allowed, node, at);
      } else {
        static_assert(std::is_same_v<X, std::string>, "one_of() needs a string field");
      }
    }
    Schema& schema_;
    size_t index_;
  };

  // A scalar or list field.
  template <class V>
  FieldBuilder<V> field(std::string key, V T::*member, std::string doc) {
    Field f;
    f.key = std::move(key);
    f.doc = std::move(doc);
    f.parse = [member](const YAML::Node& node, T& obj, const Cursor& at) { obj.*member = Codec<V>::decode(node, at); };
    f.emit = [member](const T& obj) { return Codec<V>::encode(obj.*member); };
    f.member = [member](const T& obj) -> const void* { return &(obj.*member); };
    if constexpr (is_named_enum<V>::value) f.doc += " (one of: " + join(EnumNames<V>::names()) + ")";
    fields_.push_back(std::move(f));
    return FieldBuilder<V>(*this, fields_.size() - 1);
  }

  // A nested block parsed by its own schema.
  template <class S>
  void section(std::string key, S T::*member, Schema<S> sub, std::string doc) {
    auto shared = std::make_shared<Schema<S>>(std::move(sub));
    Field f;
    f.key = std::move(key);
    f.doc = std::move(doc);
    f.parse = [member, shared](const YAML::Node& node, T& obj, const Cursor& at) { shared->parse(node, obj.*member, at); };
    f.emit = [member, shared](const T& obj) { return shared->emit(obj.*member); };
    fields_.push_back(std::move(f));
  }

  // A list of nested blocks, each parsed by `sub`.
  template <class S>
  void list(std::string key, std::vector<S> T::*member, Schema<S> sub, std::string doc) {
    auto shared = std::make_shared<Schema<S>>(std::move(sub));
    Field f;
    f.key = std::move(key);
    f.doc = std::move(doc);
    f.parse = [member, shared](const YAML::Node& node, T& obj, const Cursor& at) {
      if (!node.IsSequence()) at.fail(node, "expected a list, got " + detail::describe(node));
      std::vector<S> items;
      for (size_t i = 0; i < node.size(); ++i) {
        S item{};
        shared->parse(node[i], item, at.index(i));
        items.push_back(std::move(item));
      }
      obj.*member = std::move(items);
    };
    f.emit = [member, shared](const T& obj) {
      YAML::Node n(YAML::NodeType::Sequence);
      for (const auto& item : obj.*member) n.push_back(shared->emit(item));
      return n;
    };
    fields_.push_back(std::move(f));
  }

  // The keys of `sub` read and written at this level, stored in `member`: a block of options
  // that would otherwise repeat its owner's name (`cgsr search`'s search options). The keys sit
  // at this level, so `sub`'s older shapes do too: its moved blocks are lifted and its upgrades
  // rewrite this level's map (after this schema's own moved blocks are lifted, before its
  // fields are read), with the deprecation warnings they give.
  template <class S>
  void inline_section(S T::*member, const Schema<S>& sub) {
    for (const auto& inner : sub.fields_) {
      Field f;
      f.key = inner.key;
      f.doc = inner.doc;
      f.required = inner.required;
      f.parse = [member, p = inner.parse](const YAML::Node& node, T& obj, const Cursor& at) { p(node, obj.*member, at); };
      f.emit = [member, e = inner.emit](const T& obj) { return e(obj.*member); };
      if (inner.member) f.member = [member, m = inner.member](const T& obj) { return m(obj.*member); };
      if (inner.omit) f.omit = [member, o = inner.omit](const T& obj) { return o(obj.*member); };
      f.bounds = inner.bounds;
      if (inner.validate)
        f.validate = [member, v = inner.validate](const T& obj, const YAML::Node& node, const Cursor& at,
                                                  const void* field) { v(obj.*member, node, at, field); };
      fields_.push_back(std::move(f));
    }
    for (const auto& check : sub.cross_checks_)
      cross_checks_.push_back(
          [member, check](const T& obj, const Cursor& at, const YAML::Node& node) { check(obj.*member, at, node); });
    moved_blocks_.insert(moved_blocks_.end(), sub.moved_blocks_.begin(), sub.moved_blocks_.end());
    upgrades_.insert(upgrades_.end(), sub.upgrades_.begin(), sub.upgrades_.end());
  }

  // `old_key: {...}` of older configs, whose keys now sit at this level (e.g. `search: {strategy:
  // ..}` inside a `cgsr search` config): still read, with a deprecation warning naming the file
  // and the old and new key; a key given both ways is an error.
  void moved_block(std::string old_key) { moved_blocks_.push_back(std::move(old_key)); }

  // Rewrites an older shape of the block into the current one before parsing (after moved
  // blocks are lifted); it warns with warn_deprecated.
  void upgrade(std::function<YAML::Node(const YAML::Node&, const Cursor&)> rewrite) {
    upgrades_.push_back(std::move(rewrite));
  }

  // A raw block kept for later parsing by a factory ({type: Name, ...}).
  void block(std::string key, Block T::*member, std::string doc) {
    Field f;
    f.key = std::move(key);
    f.doc = std::move(doc);
    f.parse = [member](const YAML::Node& node, T& obj, const Cursor& at) {
      obj.*member = Block{node, std::make_shared<Document>(*at.doc), at.path};  // keeps source marks
    };
    f.emit = [member](const T& obj) { return YAML::Clone((obj.*member).node); };
    fields_.push_back(std::move(f));
  }

  // Leaves `key` out of emit() while `omit` holds: keys that do not apply (e.g. a single scene's
  // keys in a scene set), and optional keys added later, which keep older configs' resolved form
  // (and the hashes made of it) unchanged while unset.
  void omit_when(const std::string& key, std::function<bool(const T&)> omit) {
    for (auto& f : fields_)
      if (f.key == key) f.omit = omit;
  }

  // A check across fields, run after all fields are parsed (e.g. "hr size = scale x lr size").
  void validate(std::function<void(const T&, const Cursor&, const YAML::Node&)> check) {
    cross_checks_.push_back(std::move(check));
  }

  // Parses `node` (a map, or null for "all defaults") into `out`, whose fields hold the defaults.
  // Keys in `reserved` belong to the caller (e.g. `type` of a typed block) and are skipped.
  void parse(const YAML::Node& given, T& out, const Cursor& at, const std::vector<std::string>& reserved = {}) const {
    if (given && !given.IsNull() && !given.IsMap()) at.fail(given, "expected a map of keys, got " + detail::describe(given));
    YAML::Node node = moved_blocks_.empty() ? given : detail::lift_moved_blocks(given, moved_blocks_, at);
    for (const auto& rewrite : upgrades_) node = rewrite(node, at);
    std::set<std::string> seen;
    if (node && node.IsMap()) {
      for (const auto& kv : node) {
        // A list or map as a key ("? [a, b]: 1", "{a: 1}: 2") is valid YAML but names no field.
        if (!kv.first.IsScalar()) at.fail(kv.first, "a key must be a name, got " + detail::describe(kv.first));
        const std::string key = kv.first.Scalar();
        if (std::find(reserved.begin(), reserved.end(), key) != reserved.end()) continue;
        const Field* f = find(key);
        if (!f) {
          // A key written by --set has no file position; its value node knows the assignment.
          const bool overridden = at.doc && at.doc->is_override(kv.second);
          at.child(key).fail(overridden ? kv.second : kv.first, "unknown key '" + key + "'" +
                                                                    did_you_mean(key, keys()) +
                                                                    "; valid keys: " + join(keys()));
        }
        seen.insert(key);
        if (f->bounds) detail::check_range(kv.second, f->bounds->first, f->bounds->second, at.child(key));
        f->parse(kv.second, out, at.child(key));
        if (f->validate) f->validate(out, kv.second, at.child(key), f->member(out));
      }
    }
    for (const auto& f : fields_)
      if (f.required && !seen.count(f.key)) at.child(f.key).fail(node, "missing required key '" + f.key + "'");
    for (const auto& check : cross_checks_) check(out, at, node);
  }

  YAML::Node emit(const T& value) const {
    YAML::Node n(YAML::NodeType::Map);
    for (const auto& f : fields_)
      if (!f.omit || !f.omit(value)) n[f.key] = f.emit(value);
    return n;
  }

  std::vector<std::string> keys() const {
    std::vector<std::string> out;
    for (const auto& f : fields_) out.push_back(f.key);
    return out;
  }

  // "key: doc" lines, for --help texts and the README.
  std::vector<std::pair<std::string, std::string>> documentation() const {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& f : fields_) out.emplace_back(f.key, f.doc);
    return out;
  }

 private:
  struct Field {
    std::string key, doc;
    bool required = false;
    std::function<bool(const T&)> omit;
    std::function<void(const YAML::Node&, T&, const Cursor&)> parse;
    std::function<YAML::Node(const T&)> emit;
    std::function<const void*(const T&)> member;
    std::function<void(const T&, const YAML::Node&, const Cursor&, const void*)> validate;
    std::optional<std::pair<double, double>> bounds;  // range(): checked before decoding too
  };
  const Field* find(const std::string& key) const {
    for (const auto& f : fields_)
      if (f.key == key) return &f;
    return nullptr;
  }
  template <class>
  friend class Schema;  // inline_section reads another schema's fields
  std::vector<Field> fields_;
  std::vector<std::function<void(const T&, const Cursor&, const YAML::Node&)>> cross_checks_;
  std::vector<std::string> moved_blocks_;
  std::vector<std::function<YAML::Node(const YAML::Node&, const Cursor&)>> upgrades_;
};

// Parses the whole document with `schema`, starting from the defaults in T{}.
template <class T>
T parse_document(const Document& doc, const Schema<T>& schema) {
  T out{};
  schema.parse(doc.root(), out, Cursor{&doc, ""});
  return out;
}

// Parses a {type: Name, ...} block's options (every key but `type`) with `schema`.
template <class T>
T parse_block_options(const Block& block, const Schema<T>& schema) {
  T out{};
  schema.parse(block.node, out, block.cursor(), {"type"});
  return out;
}

// The `type` of a {type: Name, ...} block; an error naming the block when it is missing.
std::string block_type(const Block& block);

// Logs "<where>: <what>" as a warning once per process, however often the config is parsed
// (a deprecated key that still works).
void warn_deprecated(const std::string& where, const std::string& what);

// YAML text of a node, for config.yaml and --print-config.
std::string to_yaml(const YAML::Node& node);

}  // namespace cgsr::config
