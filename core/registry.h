#pragma once
// Name -> factory tables. One registry per kind (backbones, scene sources, dataset layouts,
// strategies, ...), each behind a function that fills it with the built-in entries on first use
// (a function-local static), never by static initializers in other files the linker may drop:
//
//   Registry<Factory>& things() {
//     static Registry<Factory> registry = [] { Registry<Factory> r("thing"); r.add(...); return r; }();
//     return registry;
//   }

#include <map>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/text.h"

namespace cgsr {

template <class Factory>
class Registry {
 public:
  explicit Registry(std::string kind) : kind_(std::move(kind)) {}

  void add(const std::string& name, Factory factory, std::string description = "") {
    if (entries_.count(name)) throw Error(kind_ + " registry", "duplicate name '" + name + "'", ErrorKind::Internal);
    entries_.emplace(name, Entry{std::move(factory), std::move(description)});
  }

  bool contains(const std::string& name) const { return entries_.count(name) > 0; }

  const Factory& get(const std::string& name) const {
    const auto it = entries_.find(name);
    if (it == entries_.end())
      throw Error(kind_, "unknown " + kind_ + " '" + name + "'" + did_you_mean(name, names()) +
                             "; valid: " + join(names()));
    return it->second.factory;
  }

  const std::string& description(const std::string& name) const {
    get(name);
    return entries_.at(name).description;
  }

  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& [name, entry] : entries_) out.push_back(name);
    return out;
  }

  const std::string& kind() const { return kind_; }

 private:
  struct Entry {
    Factory factory;
    std::string description;
  };
  std::string kind_;
  std::map<std::string, Entry> entries_;
};

}  // namespace cgsr
