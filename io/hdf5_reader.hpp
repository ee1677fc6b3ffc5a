#pragma once
// A small read-only view of an HDF5 file (results.h5), enough to check what the writer wrote
// without h5dump or h5py. Object names are absolute paths ("/frames/000000/objects");
// attributes are read from a group or dataset by name. HDF5 itself stays inside io/.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace vproxq {

class Hdf5Reader {
 public:
  /// Opens `file` read-only. Throws InputError naming the file.
  explicit Hdf5Reader(const std::filesystem::path& file);
  ~Hdf5Reader();
  Hdf5Reader(const Hdf5Reader&) = delete;
  Hdf5Reader& operator=(const Hdf5Reader&) = delete;

  /// True when every link along `object` exists.
  bool exists(const std::string& object) const;
  /// Names of the members of a group, in name order.
  std::vector<std::string> children(const std::string& group) const;
  /// Names of the attributes of a group or dataset, in name order.
  std::vector<std::string> attribute_names(const std::string& object) const;

  /// Scalar attributes, converted by HDF5 to the requested type.
  std::string string_attribute(const std::string& object, const std::string& name) const;
  std::int64_t int_attribute(const std::string& object, const std::string& name) const;
  std::uint64_t uint_attribute(const std::string& object, const std::string& name) const;
  double double_attribute(const std::string& object, const std::string& name) const;
  /// A 1-D string array attribute.
  std::vector<std::string> strings_attribute(const std::string& object,
                                             const std::string& name) const;

  /// Number of elements of a 1-D dataset.
  std::size_t rows(const std::string& dataset) const;
  /// A 1-D dataset of strings.
  std::vector<std::string> strings_dataset(const std::string& dataset) const;
  /// One field of a 1-D compound dataset, converted to int64 / double; an array field
  /// (point_a, double[3]) comes flattened row by row.
  std::vector<std::int64_t> int_field(const std::string& dataset, const std::string& field) const;
  std::vector<double> double_field(const std::string& dataset, const std::string& field) const;
  /// Names of the fields of a compound dataset, in file order.
  std::vector<std::string> field_names(const std::string& dataset) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vproxq
