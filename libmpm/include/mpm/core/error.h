#pragma once
//! Typed errors thrown at API boundaries (after OpenVDB's Exceptions.h).
//! InputError: a scene, a command line or an input file is wrong; the message names the file,
//! the line, the key path, the value and the accepted range. NumericalError: a NaN/Inf or a
//! failed solve; the message names the stage, the particle or node and the quantity.
//! IoError: a file could not be read or written.
#include <stdexcept>
#include <string>

namespace mpm {

class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};
class InputError : public Error {
public:
  using Error::Error;
};
class NumericalError : public Error {
public:
  using Error::Error;
};
class IoError : public Error {
public:
  using Error::Error;
};

//! Always-on check (MFEM_VERIFY): throws ErrorType with the message when cond is false.
template <class ErrorType = Error>
inline void verify(bool cond, const std::string& message) {
  if (!cond) throw ErrorType(message);
}

namespace detail {
//! The message of a failed MPM_VERIFY / MPM_ASSERT: what was asked, and where.
inline std::string failed_check(const char* expression, const char* file, int line, const std::string& message) {
  return message + " (check '" + expression + "' failed at " + file + ":" + std::to_string(line) + ")";
}
}  // namespace detail

}  // namespace mpm

//! Always-on check that records the expression, file and line (MFEM_VERIFY): throws
//! ErrorType(message + " (check 'cond' failed at file:line)") when cond is false.
#define MPM_VERIFY(cond, ErrorType, message)                                                         \
  do {                                                                                               \
    if (!(cond)) throw ErrorType(::mpm::detail::failed_check(#cond, __FILE__, __LINE__, (message))); \
  } while (0)

//! A programming error caught in debug builds only (MFEM_ASSERT): throws std::logic_error with
//! the expression, file and line; compiled out with NDEBUG (release builds, hot loops).
#ifndef NDEBUG
#define MPM_ASSERT(cond)                                                                                      \
  do {                                                                                                        \
    if (!(cond)) throw std::logic_error(::mpm::detail::failed_check(#cond, __FILE__, __LINE__, "assertion")); \
  } while (0)
#else
#define MPM_ASSERT(cond) ((void)0)
#endif
