#include "fuzz_support.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

namespace svbtdf::fuzz {
namespace {

std::filesystem::path MakeScratchFolder() {
  const std::filesystem::path shm = "/dev/shm";
  std::error_code error;
  const std::filesystem::path parent = std::filesystem::is_directory(shm, error) ? shm : std::filesystem::temp_directory_path();
  const std::filesystem::path folder = parent / ("svbtdf-fuzz-" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder, error);
  std::filesystem::create_directories(folder);
  return folder;
}

void RemoveScratchFolder() {
  std::error_code error;
  std::filesystem::remove_all(ScratchFolder(), error);
}

}  // namespace

const std::filesystem::path& ScratchFolder() {
  static const std::filesystem::path folder = [] {
    // SVBTDF_FUZZ_SCRATCH=DIR keeps the files, to look at what a finding's input did.
    if (const char* kept = std::getenv("SVBTDF_FUZZ_SCRATCH")) {
      std::filesystem::create_directories(kept);
      return std::filesystem::path(kept);
    }
    std::filesystem::path made = MakeScratchFolder();
    std::atexit(RemoveScratchFolder);
    return made;
  }();
  return folder;
}

void WriteInput(const std::filesystem::path& path, const uint8_t* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) FixtureBroken("cannot write the input to " + path.string());
}

void FuzzFile(const char* file_name, const uint8_t* data, size_t size,
              const std::function<void(const std::filesystem::path&)>& read) {
  static const std::filesystem::path path = ScratchFolder() / file_name;  // one file per target process
  WriteInput(path, data, size);
  ExpectOnlySvbtdfErrors([&] { read(path); });
}

std::filesystem::path CopyFixture(const std::string& name) {
  const std::filesystem::path source = std::filesystem::path(SVBTDF_FUZZ_FIXTURES) / name;
  const std::filesystem::path copy = ScratchFolder() / name;
  std::error_code error;
  std::filesystem::copy(source, copy, std::filesystem::copy_options::recursive, error);
  if (error) FixtureBroken("cannot copy " + source.string() + ": " + error.message());
  return copy;
}

void FixtureBroken(const std::string& what) {
  std::fprintf(stderr, "fuzz harness broken (not a finding): %s\n", what.c_str());
  std::exit(1);
}

}  // namespace svbtdf::fuzz
