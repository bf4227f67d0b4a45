#pragma once
// Enums that configs and files spell as text: one table of names per enum (in enum order) and the
// conversions both ways, so a name is parsed once, with a did-you-mean error, and compared as an
// enum everywhere else. config.h reads and writes such enums as config fields.
//
//   enum class Fruit { Apple, Pear };
//   template <> struct EnumNames<Fruit> {
//     static constexpr const char* kind = "fruit";
//     static const std::vector<std::string>& names() { static const std::vector<std::string> n{"apple", "pear"}; return n; }
//   };
//   enum_from_name<Fruit>("pears")  // Error("fruit", "'pears' is not one of: apple, pear; did you mean 'pear'?")
//   enum_name(Fruit::Pear)          // "pear"

#include <string>
#include <type_traits>
#include <vector>

#include "core/error.h"
#include "core/text.h"

namespace cgsr {

template <class E>
struct EnumNames;  // specialised for each named enum

template <class E, class = void>
struct is_named_enum : std::false_type {};
template <class E>
struct is_named_enum<E, std::void_t<decltype(EnumNames<E>::names())>> : std::true_type {};

// "'x' is not one of: a, b; did you mean 'a'?" (what enum_from_name and the config codec say).
template <class E>
std::string unknown_enum_name(const std::string& name) {
  const auto& names = EnumNames<E>::names();
  return "'" + name + "' is not one of: " + join(names) + did_you_mean(name, names);
}

template <class E>
E enum_from_name(const std::string& name) {
  const auto& names = EnumNames<E>::names();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<E>(i);
  throw Error(EnumNames<E>::kind, unknown_enum_name<E>(name));
}

template <class E>
const std::string& enum_name(E value) {
  return EnumNames<E>::names().at(static_cast<size_t>(value));
}

}  // namespace cgsr
