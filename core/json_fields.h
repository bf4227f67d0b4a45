#pragma once
// Plain structs to and from JSON field by field, when every JSON key is the field's name:
//
//   struct Score { double psnr = 0; std::optional<double> latency_ms; };
//   CGSR_JSON_FIELDS(Score, psnr, latency_ms)    // in Score's namespace
//   nlohmann::ordered_json j = score;            // {"psnr": ..., "latency_ms": null}, in the listed order
//   Score back = j.get<Score>();                 // a missing key throws nlohmann's out_of_range
//
// CGSR_JSON_FIELDS is nlohmann's NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE as nlohmann-json 3.11.3
// defines it (for every basic_json, so ordered_json keeps the keys in the listed order); Debian's
// 3.11.2 binds it to nlohmann::json alone, whose keys come out sorted. With 3.11.3 or later each
// use can become NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE. CGSR_JSON_FIELDS_WITH_DEFAULT reads a
// missing key as the field's default (NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT).
//
// Structs whose JSON renames a key, leaves a default out or computes a value keep a hand-written
// to_json.

#include <nlohmann/json.hpp>
#include <optional>

// Internal: the template head (every basic_json: json, ordered_json) and the shared to_json.
#define CGSR_JSON_DETAIL_TEMPLATE                                                                          \
  template <class BasicJsonType,                                                                           \
            nlohmann::detail::enable_if_t<nlohmann::detail::is_basic_json<BasicJsonType>::value, int> = 0>
#define CGSR_JSON_DETAIL_TO(Type, ...)                                                                     \
  CGSR_JSON_DETAIL_TEMPLATE void to_json(BasicJsonType& nlohmann_json_j, const Type& nlohmann_json_t) {    \
    NLOHMANN_JSON_EXPAND(NLOHMANN_JSON_PASTE(NLOHMANN_JSON_TO, __VA_ARGS__))                               \
  }

#define CGSR_JSON_FIELDS(Type, ...)                                                                        \
  CGSR_JSON_DETAIL_TO(Type, __VA_ARGS__)                                                                   \
  CGSR_JSON_DETAIL_TEMPLATE void from_json(const BasicJsonType& nlohmann_json_j, Type& nlohmann_json_t) {  \
    NLOHMANN_JSON_EXPAND(NLOHMANN_JSON_PASTE(NLOHMANN_JSON_FROM, __VA_ARGS__))                             \
  }

#define CGSR_JSON_FIELDS_WITH_DEFAULT(Type, ...)                                                           \
  CGSR_JSON_DETAIL_TO(Type, __VA_ARGS__)                                                                   \
  CGSR_JSON_DETAIL_TEMPLATE void from_json(const BasicJsonType& nlohmann_json_j, Type& nlohmann_json_t) {  \
    const Type nlohmann_json_default_obj{};                                                                \
    NLOHMANN_JSON_EXPAND(NLOHMANN_JSON_PASTE(NLOHMANN_JSON_FROM_WITH_DEFAULT, __VA_ARGS__))                \
  }

// std::optional<T> as null or its value (nlohmann-json 3.11 has no serializer for it).
namespace nlohmann {
template <class T>
struct adl_serializer<std::optional<T>> {
  template <class BasicJsonType>
  static void to_json(BasicJsonType& j, const std::optional<T>& value) {
    if (value)
      j = *value;
    else
      j = nullptr;
  }
  template <class BasicJsonType>
  static void from_json(const BasicJsonType& j, std::optional<T>& value) {
    if (j.is_null())
      value.reset();
    else
      value = j.template get<T>();
  }
};
}  // namespace nlohmann
