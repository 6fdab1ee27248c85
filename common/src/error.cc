#include "svbtdf/common/error.h"

#include <utility>

namespace svbtdf::common {
namespace {

std::string Compose(const std::string& subject, const std::string& problem,
                    const std::string& hint) {
  std::string line = subject.empty() ? problem : subject + ": " + problem;
  if (!hint.empty()) line += " (" + hint + ")";
  return line;
}

}  // namespace

Error::Error(ErrorKind kind, std::string subject, std::string problem, std::string hint)
    : std::runtime_error(Compose(subject, problem, hint)),
      kind_(kind),
      subject_(std::move(subject)),
      problem_(std::move(problem)),
      hint_(std::move(hint)) {}

void ThrowInvalidInput(const std::string& subject, const std::string& problem,
                       const std::string& hint) {
  throw Error(ErrorKind::kInvalidInput, subject, problem, hint);
}

void ThrowFormatError(const std::string& subject, const std::string& problem,
                      const std::string& hint) {
  throw Error(ErrorKind::kFormat, subject, problem, hint);
}

void ThrowIoError(const std::string& subject, const std::string& problem,
                  const std::string& hint) {
  throw Error(ErrorKind::kIo, subject, problem, hint);
}

int ExitCodeFor(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::kInvalidInput:
    case ErrorKind::kFormat:
      return 2;
    case ErrorKind::kInterrupted:
      return 130;
    case ErrorKind::kIo:
    case ErrorKind::kHardware:
    case ErrorKind::kNumerical:
      return 1;
  }
  return 1;
}

}  // namespace svbtdf::common
