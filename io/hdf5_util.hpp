#pragma once
// Internal to io/: small RAII and error helpers over the HDF5 C API, shared by the results
// writer and reader. Only io/*.cpp include this (HDF5 stays inside io/).
#include <hdf5.h>

#include <string>

namespace vproxq::h5 {

/// Owns one HDF5 identifier and closes it with the matching H5?close function.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);

  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Handle(Handle&& other) noexcept : id_(other.id_), closer_(other.closer_) { other.id_ = -1; }
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = other.id_;
      closer_ = other.closer_;
      other.id_ = -1;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  /// Closes now and reports the closer's status (negative on failure); no-op when empty.
  herr_t close() {
    herr_t status = 0;
    if (id_ >= 0 && closer_ != nullptr) status = closer_(id_);
    id_ = -1;
    return status;
  }

 private:
  void reset() { close(); }

  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

/// Silences HDF5's automatic error-stack printing for its lifetime (errors are reported
/// through exceptions instead), restoring the previous handler afterwards.
class QuietErrors {
 public:
  QuietErrors() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietErrors() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
  QuietErrors(const QuietErrors&) = delete;
  QuietErrors& operator=(const QuietErrors&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

/// The innermost message of the current HDF5 error stack (often carrying errno text), or "".
std::string last_error_message();

/// "H5Dcreate2 failed for FILE (OBJECT): detail" — the text of every HDF5 exception.
std::string failure_text(const char* call, const std::string& file, const std::string& object);

/// A variable-length UTF-8 string type (caller owns the handle).
Handle vlen_string_type();

}  // namespace vproxq::h5
