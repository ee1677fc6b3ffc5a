#include "io/hdf5_reader.hpp"

#include "core/errors.hpp"
#include "io/hdf5_util.hpp"

namespace vproxq {

namespace {

using h5::Handle;

herr_t collect_attribute_name(hid_t /*owner*/, const char* name, const H5A_info_t* /*info*/,
                              void* client) {
  static_cast<std::vector<std::string>*>(client)->emplace_back(name);
  return 0;
}

}  // namespace

struct Hdf5Reader::Impl {
  std::string path;
  Handle file;

  [[noreturn]] void fail(const char* call, const std::string& object) const {
    throw InputError("HDF5: " + h5::failure_text(call, path, object));
  }
  hid_t check_id(hid_t id, const char* call, const std::string& object) const {
    if (id < 0) fail(call, object);
    return id;
  }
  void check_ok(herr_t status, const char* call, const std::string& object) const {
    if (status < 0) fail(call, object);
  }

  Handle open_object(const std::string& object) const {
    return Handle(check_id(H5Oopen(file.get(), object.c_str(), H5P_DEFAULT), "H5Oopen", object),
                  H5Oclose);
  }
  Handle open_dataset(const std::string& dataset) const {
    return Handle(
        check_id(H5Dopen2(file.get(), dataset.c_str(), H5P_DEFAULT), "H5Dopen2", dataset),
        H5Dclose);
  }
  Handle open_attribute(const std::string& object, const std::string& name) const {
    return Handle(check_id(H5Aopen_by_name(file.get(), object.c_str(), name.c_str(), H5P_DEFAULT,
                                           H5P_DEFAULT),
                           "H5Aopen_by_name", object + "@" + name),
                  H5Aclose);
  }

  template <class T>
  T scalar_attribute(const std::string& object, const std::string& name, hid_t mem_type) const {
    Handle attr = open_attribute(object, name);
    T value{};
    check_ok(H5Aread(attr.get(), mem_type, &value), "H5Aread", object + "@" + name);
    return value;
  }

  // Reads all strings of an attribute (is_attribute) or dataset, variable or fixed length.
  std::vector<std::string> read_strings(hid_t id, bool is_attribute,
                                        const std::string& where) const {
    Handle type(check_id(is_attribute ? H5Aget_type(id) : H5Dget_type(id), "H5?get_type", where),
                H5Tclose);
    Handle space(
        check_id(is_attribute ? H5Aget_space(id) : H5Dget_space(id), "H5?get_space", where),
        H5Sclose);
    const hssize_t n = H5Sget_simple_extent_npoints(space.get());
    if (n < 0) fail("H5Sget_simple_extent_npoints", where);
    std::vector<std::string> out;
    if (n == 0) return out;
    const auto count = static_cast<std::size_t>(n);
    const htri_t variable = H5Tis_variable_str(type.get());
    if (variable < 0) fail("H5Tis_variable_str", where);
    if (variable > 0) {
      Handle mem = h5::vlen_string_type();
      if (!mem.valid()) fail("H5Tcopy", where);
      std::vector<char*> texts(count, nullptr);
      const herr_t status = is_attribute
                                ? H5Aread(id, mem.get(), texts.data())
                                : H5Dread(id, mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                          texts.data());
      check_ok(status, "H5?read", where);
      for (char* t : texts) out.emplace_back(t != nullptr ? t : "");
      H5Dvlen_reclaim(mem.get(), space.get(), H5P_DEFAULT, texts.data());
      return out;
    }
    const std::size_t size = H5Tget_size(type.get());
    Handle mem(check_id(H5Tcopy(H5T_C_S1), "H5Tcopy", where), H5Tclose);
    check_ok(H5Tset_size(mem.get(), size), "H5Tset_size", where);
    std::vector<char> buffer(size * count);
    const herr_t status =
        is_attribute ? H5Aread(id, mem.get(), buffer.data())
                     : H5Dread(id, mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data());
    check_ok(status, "H5?read", where);
    for (std::size_t i = 0; i < count; ++i) {
      const char* begin = buffer.data() + i * size;
      std::size_t len = 0;
      while (len < size && begin[len] != '\0') ++len;
      out.emplace_back(begin, len);
    }
    return out;
  }

  std::size_t rows(hid_t dataset, const std::string& where) const {
    Handle space(check_id(H5Dget_space(dataset), "H5Dget_space", where), H5Sclose);
    const hssize_t n = H5Sget_simple_extent_npoints(space.get());
    if (n < 0) fail("H5Sget_simple_extent_npoints", where);
    return static_cast<std::size_t>(n);
  }

  // One compound field, converted to `native` (array fields to arrays of `native`).
  template <class T>
  std::vector<T> field(const std::string& dataset, const std::string& name, hid_t native) const {
    const std::string where = dataset + "." + name;
    Handle ds = open_dataset(dataset);
    Handle file_type(check_id(H5Dget_type(ds.get()), "H5Dget_type", dataset), H5Tclose);
    const int index = H5Tget_member_index(file_type.get(), name.c_str());
    if (index < 0) fail("H5Tget_member_index", where);
    Handle member(check_id(H5Tget_member_type(file_type.get(), static_cast<unsigned>(index)),
                           "H5Tget_member_type", where),
                  H5Tclose);
    std::size_t per_row = 1;
    Handle element;
    if (H5Tget_class(member.get()) == H5T_ARRAY) {
      const int ndims = H5Tget_array_ndims(member.get());
      if (ndims < 1) fail("H5Tget_array_ndims", where);
      std::vector<hsize_t> dims(static_cast<std::size_t>(ndims));
      check_ok(H5Tget_array_dims2(member.get(), dims.data()), "H5Tget_array_dims2", where);
      for (hsize_t d : dims) per_row *= static_cast<std::size_t>(d);
      element = Handle(check_id(H5Tarray_create2(native, static_cast<unsigned>(ndims),
                                                 dims.data()),
                                "H5Tarray_create2", where),
                       H5Tclose);
    } else {
      element = Handle(check_id(H5Tcopy(native), "H5Tcopy", where), H5Tclose);
    }
    Handle mem(check_id(H5Tcreate(H5T_COMPOUND, sizeof(T) * per_row), "H5Tcreate", where),
               H5Tclose);
    check_ok(H5Tinsert(mem.get(), name.c_str(), 0, element.get()), "H5Tinsert", where);
    std::vector<T> out(rows(ds.get(), dataset) * per_row);
    if (!out.empty()) {
      check_ok(H5Dread(ds.get(), mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), "H5Dread",
               where);
    }
    return out;
  }
};

Hdf5Reader::Hdf5Reader(const std::filesystem::path& file) : impl_(std::make_unique<Impl>()) {
  h5::QuietErrors quiet;
  impl_->path = file.string();
  impl_->file = Handle(impl_->check_id(H5Fopen(impl_->path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                                       "H5Fopen", ""),
                       H5Fclose);
}

Hdf5Reader::~Hdf5Reader() {
  h5::QuietErrors quiet;
  impl_.reset();
}

bool Hdf5Reader::exists(const std::string& object) const {
  h5::QuietErrors quiet;
  std::string prefix;
  std::size_t start = 0;
  while (start <= object.size()) {
    std::size_t end = object.find('/', start);
    if (end == std::string::npos) end = object.size();
    if (end > start) {
      prefix += "/" + object.substr(start, end - start);
      const htri_t found = H5Lexists(impl_->file.get(), prefix.c_str(), H5P_DEFAULT);
      if (found < 0) impl_->fail("H5Lexists", prefix);
      if (found == 0) return false;
    }
    start = end + 1;
  }
  return true;
}

std::vector<std::string> Hdf5Reader::children(const std::string& group) const {
  h5::QuietErrors quiet;
  Handle g(impl_->check_id(H5Gopen2(impl_->file.get(), group.c_str(), H5P_DEFAULT), "H5Gopen2",
                           group),
           H5Gclose);
  H5G_info_t info;
  impl_->check_ok(H5Gget_info(g.get(), &info), "H5Gget_info", group);
  std::vector<std::string> names;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t size = H5Lget_name_by_idx(g.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr,
                                            0, H5P_DEFAULT);
    if (size < 0) impl_->fail("H5Lget_name_by_idx", group);
    std::string name(static_cast<std::size_t>(size) + 1, '\0');
    if (H5Lget_name_by_idx(g.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(),
                           H5P_DEFAULT) < 0) {
      impl_->fail("H5Lget_name_by_idx", group);
    }
    name.resize(static_cast<std::size_t>(size));
    names.push_back(std::move(name));
  }
  return names;
}

std::vector<std::string> Hdf5Reader::attribute_names(const std::string& object) const {
  h5::QuietErrors quiet;
  Handle obj = impl_->open_object(object);
  std::vector<std::string> names;
  impl_->check_ok(H5Aiterate2(obj.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr,
                              collect_attribute_name, &names),
                  "H5Aiterate2", object);
  return names;
}

std::string Hdf5Reader::string_attribute(const std::string& object,
                                         const std::string& name) const {
  h5::QuietErrors quiet;
  Handle attr = impl_->open_attribute(object, name);
  std::vector<std::string> values = impl_->read_strings(attr.get(), true, object + "@" + name);
  if (values.size() != 1) impl_->fail("string_attribute (not a scalar)", object + "@" + name);
  return values.front();
}

std::int64_t Hdf5Reader::int_attribute(const std::string& object, const std::string& name) const {
  h5::QuietErrors quiet;
  return impl_->scalar_attribute<std::int64_t>(object, name, H5T_NATIVE_INT64);
}

std::uint64_t Hdf5Reader::uint_attribute(const std::string& object,
                                         const std::string& name) const {
  h5::QuietErrors quiet;
  return impl_->scalar_attribute<std::uint64_t>(object, name, H5T_NATIVE_UINT64);
}

double Hdf5Reader::double_attribute(const std::string& object, const std::string& name) const {
  h5::QuietErrors quiet;
  return impl_->scalar_attribute<double>(object, name, H5T_NATIVE_DOUBLE);
}

std::vector<std::string> Hdf5Reader::strings_attribute(const std::string& object,
                                                       const std::string& name) const {
  h5::QuietErrors quiet;
  Handle attr = impl_->open_attribute(object, name);
  return impl_->read_strings(attr.get(), true, object + "@" + name);
}

std::size_t Hdf5Reader::rows(const std::string& dataset) const {
  h5::QuietErrors quiet;
  Handle ds = impl_->open_dataset(dataset);
  return impl_->rows(ds.get(), dataset);
}

std::vector<std::string> Hdf5Reader::strings_dataset(const std::string& dataset) const {
  h5::QuietErrors quiet;
  Handle ds = impl_->open_dataset(dataset);
  return impl_->read_strings(ds.get(), false, dataset);
}

std::vector<std::int64_t> Hdf5Reader::int_field(const std::string& dataset,
                                                const std::string& field) const {
  h5::QuietErrors quiet;
  return impl_->field<std::int64_t>(dataset, field, H5T_NATIVE_INT64);
}

std::vector<double> Hdf5Reader::double_field(const std::string& dataset,
                                             const std::string& field) const {
  h5::QuietErrors quiet;
  return impl_->field<double>(dataset, field, H5T_NATIVE_DOUBLE);
}

std::vector<std::string> Hdf5Reader::field_names(const std::string& dataset) const {
  h5::QuietErrors quiet;
  Handle ds = impl_->open_dataset(dataset);
  Handle type(impl_->check_id(H5Dget_type(ds.get()), "H5Dget_type", dataset), H5Tclose);
  const int n = H5Tget_nmembers(type.get());
  if (n < 0) impl_->fail("H5Tget_nmembers", dataset);
  std::vector<std::string> names;
  for (int i = 0; i < n; ++i) {
    char* name = H5Tget_member_name(type.get(), static_cast<unsigned>(i));
    if (name == nullptr) impl_->fail("H5Tget_member_name", dataset);
    names.emplace_back(name);
    H5free_memory(name);
  }
  return names;
}

}  // namespace vproxq
