// svbtdf.Session: a capture session (docs/session-format.md) read through session::Session, as
// `svbtdf session verify` and the pipeline read it.

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>

#include "bindings.h"
#include "svbtdf/common/json.h"
#include "svbtdf/session/session.h"

namespace svbtdf::python {
namespace {

py::dict EntryToPython(const session::SessionEntry& e) {
  py::dict d;
  d["key"] = e.key;
  d["file"] = e.file;
  d["bytes"] = e.bytes;
  d["crc32"] = e.crc32;
  d["exposure_s"] = e.exposure_s;
  d["gain"] = e.gain;
  d["time"] = e.time;
  return d;
}

// A camera image as uint16 (H, W) for one channel, (H, W, C) for more; values as stored.
py::array_t<uint16_t> ImageToArray(const common::CameraImage& image) {
  std::vector<py::ssize_t> shape = {image.height, image.width};
  if (image.channels != 1) shape.push_back(image.channels);
  py::array_t<uint16_t> array(shape);
  std::copy(image.pixels.begin(), image.pixels.end(), array.mutable_data());
  return array;
}

py::dict VerificationToPython(const session::SessionVerification& v) {
  py::dict d;
  d["complete"] = v.complete();
  d["missing"] = v.missing;
  d["corrupt"] = v.corrupt;
  d["duplicated"] = v.duplicated;
  d["unexpected"] = v.unexpected;
  d["summary"] = v.Summary();
  return d;
}

}  // namespace

void BindSession(py::module_& m) {
  py::class_<session::Session>(m, "Session",
                               "A capture session (docs/session-format.md): manifest, rig, plan, journal and images. "
                               "Open with Session.open(path).")
      .def_static("open", [](const std::string& path) { return std::make_unique<session::Session>(session::Session::Open(path)); },
                  py::arg("path"),
                  "Opens SESSION/ and checks its manifest, plan and journal. Raises svbtdf.FormatError or "
                  "svbtdf.IoError naming the file (and the journal's line).")
      .def_property_readonly("path", [](const session::Session& s) { return s.folder().string(); })
      .def_property_readonly("manifest", [](const session::Session& s) { return ToPython(common::ReadJsonFile(s.folder() / "session.json")); },
                             "session.json as a dict (format, version, rig, software)")
      .def_property_readonly("rig", [](const session::Session& s) { return ToPython(s.rig_json()); },
                             "the manifest's rig description as a dict (camera, sensor window, sample, monitor, dots, boards)")
      .def_property_readonly("plan", [](const session::Session& s) { return s.planned_keys(); },
                             "the planned capture keys, in capture order (list of str)")
      .def_property_readonly("journal", [](const session::Session& s) {
            py::list out;
            for (const session::SessionEntry& e : s.entries()) out.append(EntryToPython(e));
            return out;
          }, "the journalled images in order: dicts with key, file, bytes, crc32, exposure_s, gain, time")
      .def("__contains__", &session::Session::Contains, py::arg("key"), "whether `key` is journalled")
      .def("image", [](const session::Session& s, const std::string& key, bool check_crc) {
            common::CameraImage image;
            {
              py::gil_scoped_release release;
              image = s.ReadImage(key, check_crc);
            }
            return ImageToArray(image);
          }, py::arg("key"), py::arg("check_crc") = false,
          "The image journalled under a capture key (e.g. 'dot/q0012/e1/r0') as uint16 (H, W) or (H, W, 3), values "
          "as stored (8-bit files too). Raises svbtdf.InvalidInputError for a key not journalled, "
          "svbtdf.IoError/FormatError for a damaged file.")
      .def("verify", [](const session::Session& s, bool check_crc, bool decode) {
            session::SessionVerification v;
            {
              py::gil_scoped_release release;
              v = s.Verify(check_crc, decode);
            }
            return VerificationToPython(v);
          }, py::arg("check_crc") = true, py::arg("decode") = false,
          "`svbtdf session verify [--no-crc] [--decode]`: dict with complete (bool), missing, corrupt, duplicated, "
          "unexpected (lists of keys) and summary (str).");
}

}  // namespace svbtdf::python
