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

}  // namespace mpm
