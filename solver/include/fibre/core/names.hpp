// One name table per enum: to_string, parse and the list of choices all read it.
//
// An enum E opts in by specialising EnumNames<E> with a `table` of {value, name, alias}
// entries. The first entry of a value is its name; aliases are accepted by parse() only.
#pragma once

#include <string>
#include <type_traits>

namespace fibre {

template <class E> struct EnumName {
  E value;
  const char *name;
  bool alias = false;
};

template <class E> struct EnumNames; // specialised next to each enum

template <class E, class = decltype(EnumNames<E>::table)> const char *to_string(E value)
{
  for (const auto &entry : EnumNames<E>::table)
    if (entry.value == value) return entry.name;
  return "unknown";
}

template <class E, class = decltype(EnumNames<E>::table)>
bool parse(const std::string &text, E &value)
{
  for (const auto &entry : EnumNames<E>::table)
    if (text == entry.name) {
      value = entry.value;
      return true;
    }
  return false;
}

// "a|b|c": the names a user may type, aliases left out.
template <class E, class = decltype(EnumNames<E>::table)> std::string choices()
{
  std::string out;
  for (const auto &entry : EnumNames<E>::table) {
    if (entry.alias) continue;
    if (!out.empty()) out += '|';
    out += entry.name;
  }
  return out;
}

} // namespace fibre
