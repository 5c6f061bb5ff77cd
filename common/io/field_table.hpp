#pragma once
// A struct's scalar fields named once, in one table that both the writer and
// the reader of an artifact walk: a field added to the table is written and
// read back under the same name, and the two cannot drift apart. A struct is
// stored as attributes of one object; a vector of structs (a history) as one
// dataset per field, the table's columns.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "core/errors.hpp"
#include "io/hdf5_file.hpp"

namespace msfab {

template <class S>
struct FieldOf {
  const char* name;
  std::variant<double S::*, std::int32_t S::*, std::int64_t S::*, std::string S::*> member;
};

// The field whose attribute is named as the member: MSFAB_FIELD(DacModel, damping_a).
#define MSFAB_FIELD(S, member) \
  ::msfab::FieldOf<S> { #member, &S::member }

template <class S, std::size_t N>
void write_attribute_fields(H5File& f, const std::string& object, const S& s, const FieldOf<S> (&fields)[N]) {
  for (const FieldOf<S>& field : fields)
    std::visit([&](auto member) { f.write_attribute(object, field.name, s.*member); }, field.member);
}

// Every field must be present; a missing one is an InputError naming it.
template <class S, std::size_t N>
void read_attribute_fields(const H5File& f, const std::string& object, S& s, const FieldOf<S> (&fields)[N]) {
  for (const FieldOf<S>& field : fields)
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(s.*member)>;
          if constexpr (std::is_same_v<T, std::string>)
            s.*member = f.read_string_attribute(object, field.name);
          else
            s.*member = f.read_attribute<T>(object, field.name);
        },
        field.member);
}

// One dataset group/<name> per field, nothing when `rows` is empty. A table
// with a string field is a programming error here (std::logic_error).
template <class S, std::size_t N>
void write_column_fields(H5File& f, const std::string& group, const std::vector<S>& rows,
                         const FieldOf<S> (&fields)[N]) {
  if (rows.empty()) return;
  for (const FieldOf<S>& field : fields)
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(rows[0].*member)>;
          if constexpr (std::is_same_v<T, std::string>) {
            throw std::logic_error(std::string("write_column_fields: string field '") + field.name + "'");
          } else {
            std::vector<T> column;
            column.reserve(rows.size());
            for (const S& row : rows) column.push_back(row.*member);
            f.write_vector(group + "/" + field.name, column);
          }
        },
        field.member);
}

// The rows written by write_column_fields; none when the group is absent.
// InputError naming the file and group when the columns differ in length.
template <class S, std::size_t N>
std::vector<S> read_column_fields(const H5File& f, const std::string& group, const FieldOf<S> (&fields)[N]) {
  std::vector<S> rows;
  if (!f.exists(group)) return rows;
  for (std::size_t k = 0; k < N; ++k)
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(rows[0].*member)>;
          const std::string path = group + "/" + fields[k].name;
          if constexpr (std::is_same_v<T, std::string>) {
            throw std::logic_error("read_column_fields: string field '" + path + "'");
          } else {
            const std::vector<T> column = f.read_vector<T>(path);
            if (k == 0) rows.resize(column.size());
            if (column.size() != rows.size())
              throw InputError(f.path() + ": dataset '" + path + "' has " + std::to_string(column.size()) +
                               " entries, expected " + std::to_string(rows.size()) + " like the other columns of '" +
                               group + "'");
            for (std::size_t i = 0; i < rows.size(); ++i) rows[i].*member = column[i];
          }
        },
        fields[k].member);
  return rows;
}

}  // namespace msfab
