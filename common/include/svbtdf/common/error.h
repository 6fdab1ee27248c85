#pragma once
// The one error convention of svbtdf: every module boundary throws svbtdf::Error.
// An Error says what went wrong, which file or argument it concerns (the "subject") and,
// where we can tell, what the user should do about it. The command line turns it into
// one line on stderr and an exit code chosen by its kind.

#include <stdexcept>
#include <string>

namespace svbtdf::common {

enum class ErrorKind {
  kInvalidInput,  // a bad argument or a bad value in a file the user handed in
  kFormat,        // a file that cannot be parsed or has the wrong version/shape
  kIo,            // a file or folder that cannot be read or written
  kHardware,      // a camera or display that failed or vanished
  kNumerical,     // a computation that did not converge or produced non-finite values
  kInterrupted,   // the user asked us to stop (SIGINT); work done so far is kept
};

class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, std::string subject, std::string problem, std::string hint = {});

  ErrorKind kind() const { return kind_; }
  const std::string& subject() const { return subject_; }
  const std::string& problem() const { return problem_; }
  const std::string& hint() const { return hint_; }

 private:
  ErrorKind kind_;
  std::string subject_;
  std::string problem_;
  std::string hint_;
};

// Shorthands for the common kinds. `subject` names the file, argument or device.
[[noreturn]] void ThrowInvalidInput(const std::string& subject, const std::string& problem,
                                    const std::string& hint = {});
[[noreturn]] void ThrowFormatError(const std::string& subject, const std::string& problem,
                                   const std::string& hint = {});
[[noreturn]] void ThrowIoError(const std::string& subject, const std::string& problem,
                               const std::string& hint = {});

// Process exit code for an error of this kind (2 for bad input, 130 for interruption, else 1).
int ExitCodeFor(ErrorKind kind);

}  // namespace svbtdf::common
