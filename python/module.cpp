// tendril._tendril: the Session as a Python module (docs/python.md).
//
// Everything goes through session::Session and its Editor, as in the CLI and the studio: the
// same scene file grown here and by `tendril grow` writes the same bytes. Arrays of a plant's
// skeleton and of meshed geometry are numpy views of the snapshot or mesh they belong to (the
// Python object keeps it alive; the views are read-only). Errors are tendril.Error, carrying
// the one-line message and its source and location. Growing, meshing, exporting, rendering and
// file I/O release the GIL; a Session serialises its own calls with a mutex, so two threads may
// share one, and two Sessions grow in parallel.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/io/export_model.h"
#include "tendril/lsystem/grammar_files.h"
#include "tendril/models/species_presets.h"
#include "tendril/render/impostor_baker.h"
#include "tendril/render/session_render.h"
#include "tendril/scene/model_types.h"
#include "tendril/scene/scene.h"
#include "tendril/scene/settings_schema.h"
#include "tendril/session/edit.h"
#include "tendril/session/edit_script.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"
#include "tendril/session/session_file.h"
#include "tendril/wind/gltf_animation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

namespace py = pybind11;
using namespace tendril;

namespace {

// --- errors ---------------------------------------------------------------------------------

PyObject* gErrorType = nullptr;    // tendril.Error, created at import (lives as long as the module)
PyObject* gWarningType = nullptr;  // tendril.TendrilWarning

// --- Python values <-> JSON -------------------------------------------------------------------

constexpr int kMaxDepth = 256;

Json toJson(py::handle v, const std::string& where, int depth = 0) {
  if (depth > kMaxDepth) throw Error("<python>", where, "is nested too deeply");
  if (v.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>();
  if (py::isinstance<py::int_>(v)) {
    try {
      return v.cast<int64_t>();
    } catch (const py::cast_error&) {
      throw Error("<python>", where, "is an integer out of the 64-bit range");
    }
  }
  if (py::isinstance<py::float_>(v)) return v.cast<double>();
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  if (py::isinstance<py::dict>(v)) {
    Json o = Json::object();
    for (auto item : v.cast<py::dict>()) {
      if (!py::isinstance<py::str>(item.first))
        throw Error("<python>", where, fmt::format("has a key that is not a string ({})", std::string(py::repr(item.first))));
      const std::string key = item.first.cast<std::string>();
      o[key] = toJson(item.second, where + "/" + key, depth + 1);
    }
    return o;
  }
  // numpy arrays and scalars: as the lists and numbers they hold.
  if (py::hasattr(v, "tolist") && !py::isinstance<py::list>(v) && !py::isinstance<py::tuple>(v))
    return toJson(v.attr("tolist")(), where, depth + 1);
  if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
    Json a = Json::array();
    size_t i = 0;
    for (py::handle e : v) a.push_back(toJson(e, where + "/" + std::to_string(i++), depth + 1));
    return a;
  }
  throw Error("<python>", where,
              fmt::format("cannot be given to Tendril: a {} (expected dict, list, str, number, bool or None)",
                          std::string(py::str(v.get_type().attr("__name__")))));
}

py::object fromJson(const Json& j) {
  switch (j.type()) {
    case Json::value_t::null: return py::none();
    case Json::value_t::boolean: return py::bool_(j.get<bool>());
    case Json::value_t::number_integer: return py::int_(j.get<int64_t>());
    case Json::value_t::number_unsigned: return py::int_(j.get<uint64_t>());
    case Json::value_t::number_float: return py::float_(j.get<double>());
    case Json::value_t::string: return py::str(j.get_ref<const std::string&>());
    case Json::value_t::array: {
      py::list l;
      for (const Json& e : j) l.append(fromJson(e));
      return l;
    }
    case Json::value_t::object: {
      py::dict d;
      for (auto it = j.begin(); it != j.end(); ++it) d[py::str(it.key())] = fromJson(it.value());
      return d;
    }
    default: return py::none();
  }
}

// --- read-only numpy views ------------------------------------------------------------------

// A view of `count` rows of `cols` values of T at `data`, kept alive by `owner`.
template <class T>
py::array view(const T* data, size_t count, size_t cols, py::handle owner) {
  std::vector<py::ssize_t> shape = {py::ssize_t(count)}, strides = {py::ssize_t(cols * sizeof(T))};
  if (cols > 1) {
    shape.push_back(py::ssize_t(cols));
    strides.push_back(py::ssize_t(sizeof(T)));
  }
  static const T kEmpty{};
  py::array a(py::dtype::of<T>(), shape, strides, count ? data : &kEmpty, owner);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}
// Eigen vectors of floats are packed (Vec3: 12 bytes, Vec2: 8, Quat: x y z w).
static_assert(sizeof(Vec3) == 3 * sizeof(float) && sizeof(Vec2) == 2 * sizeof(float) && sizeof(Quat) == 4 * sizeof(float));
inline const float* floats(const std::vector<Vec3>& v) { return v.empty() ? nullptr : v[0].data(); }
inline const float* floats(const std::vector<Vec2>& v) { return v.empty() ? nullptr : v[0].data(); }
inline const float* floats(const std::vector<Quat>& v) { return v.empty() ? nullptr : v[0].coeffs().data(); }

// --- plants ---------------------------------------------------------------------------------

struct PyPlant {
  plant::PlantModel model;
  std::string modelType;
};

// --- meshes ---------------------------------------------------------------------------------

struct PyModel {
  io::ExportModel model;
};
struct PyPart {
  std::shared_ptr<PyModel> owner;
  size_t object = 0, part = 0;
  const io::ExportPart& get() const { return owner->model.objects.at(object).parts.at(part); }
};

std::string materialKind(io::ExportMaterial::Kind k) {
  switch (k) {
    case io::ExportMaterial::Kind::Bark: return "bark";
    case io::ExportMaterial::Kind::Leaf: return "leaf";
    case io::ExportMaterial::Kind::Impostor: return "impostor";
    default: return "plain";
  }
}

// --- the session ----------------------------------------------------------------------------

class PySession {
 public:
  PySession(std::unique_ptr<session::Session> s, std::vector<session::TimedEdit> journal, std::string source)
      : session_(std::move(s)), editor_(std::make_unique<session::Editor>(*session_)), source_(std::move(source)) {
    if (!journal.empty()) editor_->setJournal(std::move(journal));
  }

  static std::unique_ptr<PySession> fromScene(const py::dict& scene, const std::string& baseDir, const std::string& source) {
    Json doc = toJson(scene, "");
    std::vector<std::string> caught;
    std::unique_ptr<PySession> s;
    {
      py::gil_scoped_release release;
      log::ThreadCapture capture(&caught);
      std::filesystem::path dir = baseDir.empty() ? std::filesystem::current_path() : std::filesystem::absolute(baseDir);
      scene::Scene sc = scene::parseScene(doc, source, dir);
      s = std::make_unique<PySession>(std::make_unique<session::Session>(std::move(sc), std::move(doc), dir),
                                      std::vector<session::TimedEdit>{}, source);
    }
    s->deliver(caught);
    return s;
  }

  static std::unique_ptr<PySession> open(const std::string& path) {
    std::vector<std::string> caught;
    std::unique_ptr<PySession> s;
    {
      py::gil_scoped_release release;
      log::ThreadCapture capture(&caught);
      if (session::isSessionFile(path)) {
        session::LoadedSession loaded = session::loadSession(path);
        s = std::make_unique<PySession>(std::move(loaded.session), std::move(loaded.journal), path);
      } else {
        s = std::make_unique<PySession>(session::Session::open(path), std::vector<session::TimedEdit>{}, path);
      }
    }
    s->deliver(caught);
    return s;
  }

  // Runs f with the GIL released and this session's lock held; the warnings Tendril writes on
  // this thread meanwhile become the session's (and Python warnings) rather than stderr lines.
  template <class F>
  auto locked(F&& f) {
    std::vector<std::string> caught;
    auto call = [&] {
      py::gil_scoped_release release;
      std::lock_guard lock(mutex_);
      log::ThreadCapture capture(&caught);
      return f();
    };
    try {
      if constexpr (std::is_void_v<decltype(call())>) {
        call();
        deliver(caught);
      } else {
        auto result = call();
        deliver(caught);
        return result;
      }
    } catch (const py::error_already_set&) {
      throw;
    } catch (...) {
      warnings_.insert(warnings_.end(), caught.begin(), caught.end());
      throw;
    }
  }

  // Keeps the warnings and issues each as a tendril.TendrilWarning (GIL held).
  void deliver(std::vector<std::string>& caught) {
    for (std::string& m : caught) {
      warnings_.push_back(m);
      if (PyErr_WarnEx(gWarningType, m.c_str(), 1) < 0) throw py::error_already_set();
    }
    caught.clear();
  }
  const std::vector<std::string>& warnings() const { return warnings_; }

  void step(uint32_t count) {
    locked([&] { editor_->step(count); });
  }

  // Up to `steps` steps (the scene's "steps" when None), stopping early when nothing grows, as
  // `tendril grow` does. progress(done) after each step.
  uint32_t run(std::optional<int64_t> steps, const std::optional<py::function>& progress) {
    if (steps && *steps < 0) throw Error("<python>", "steps", fmt::format("must be >= 0, got {}", *steps));
    return locked([&] {
      const uint32_t total = steps ? uint32_t(std::min<int64_t>(*steps, 100'000'000)) : uint32_t(session_->scene().steps);
      uint32_t done = 0;
      while (done < total && !session_->finished()) {
        editor_->step(1);
        ++done;
        if (progress) {
          py::gil_scoped_acquire acquire;
          (*progress)(done);
        }
      }
      session_->reportGrowth();  // plants that stopped early, and why: TendrilWarnings
      return done;
    });
  }

  session::Session& session() { return *session_; }
  session::Editor& editor() { return *editor_; }
  std::mutex& mutex() { return mutex_; }
  const std::string& source() const { return source_; }

 private:
  std::unique_ptr<session::Session> session_;
  std::unique_ptr<session::Editor> editor_;
  std::string source_;
  std::mutex mutex_;
  std::vector<std::string> warnings_;
};

session::Edit readEditDict(const py::dict& d) {
  const Json j = toJson(d, "");
  JsonObject o(j, "<python>");
  session::Edit e = session::readEdit(o);
  o.finish();
  return e;
}

std::shared_ptr<PyModel> meshSession(PySession& s) {
  auto m = std::make_shared<PyModel>();
  s.locked([&] {
    const session::Session& session = s.session();
    m->model = io::buildExportModel(session::exportScene(session, s.source()), session::exportOptions(session.scene().output));
  });
  return m;
}

py::list windFrames(PySession& s, float seconds, int fps, const std::optional<py::dict>& windDict) {
  if (!(seconds > 0.0f) || seconds > 600.0f) throw Error("<python>", "seconds", fmt::format("must be in (0, 600], got {}", seconds));
  if (fps < 1 || fps > 240) throw Error("<python>", "fps", fmt::format("must be in [1, 240], got {}", fps));
  // Another wind than the scene's for the motion only (the plants as grown): a scene's "wind"
  // object, analytic (constant or gusty).
  std::optional<env::WindField> other;
  if (windDict) {
    const Json j = toJson(*windDict, "/wind");
    JsonObject o(j, "<python>", "/wind");
    env::WindSettings w = scene::readWind(o);
    o.finish();
    if (w.mode == env::WindMode::Sph)
      throw Error("<python>", "/wind/mode", "wind_frames takes an analytic wind (constant or gusty), not sph");
    for (env::WindEmitter& em : w.emitters) em = scene::normalised(em);
    other.emplace(std::move(w));
  }
  // Per frame, per part of mesh() (objects in order, their parts in order): the posed positions.
  std::vector<std::vector<std::vector<Vec3>>> frames;
  s.locked([&] {
    const session::Session& session = s.session();
    const io::ExportScene exported = session::exportScene(session, s.source());
    const io::ExportOptions options = session::exportOptions(session.scene().output);
    const io::ExportModel rest = io::buildExportModel(exported, options);
    wind::WindAnimationOptions a = session::windClipOptions(session, seconds);
    a.fps = fps;
    const std::vector<wind::AnimatedPlant> animated = session::animatedPlants(session, exported);
    wind::forEachWindFrame(animated, other ? *other : session.environment().windField(), a, s.source(),
                           [&](int k, const std::vector<plant::PlantModel>& posed) {
      io::ExportScene scene;
      scene.plants = posed;
      scene.meshes = exported.meshes;
      const io::ExportModel model = io::buildExportModel(scene, options);
      if (model.objects.size() != rest.objects.size())
        throw Error(s.source(), fmt::format("frame {}", k), "the posed plants mesh to other objects than at rest");
      std::vector<std::vector<Vec3>>& parts = frames.emplace_back();
      for (size_t o = 0; o < model.objects.size(); ++o) {
        const auto& posedParts = model.objects[o].parts;
        const auto& restParts = rest.objects[o].parts;
        if (posedParts.size() != restParts.size())
          throw Error(s.source(), fmt::format("frame {}", k), fmt::format("object \"{}\" meshes to other parts than at rest", model.objects[o].name));
        for (size_t p = 0; p < posedParts.size(); ++p) {
          if (posedParts[p].mesh->vertexCount() != restParts[p].mesh->vertexCount())
            throw Error(s.source(), fmt::format("frame {}", k),
                        fmt::format("part \"{}\" of \"{}\" has {} vertices posed, {} at rest", posedParts[p].name,
                                    model.objects[o].name, posedParts[p].mesh->vertexCount(), restParts[p].mesh->vertexCount()));
          parts.push_back(posedParts[p].mesh->positions);
        }
      }
    });
  });
  py::list out;
  for (auto& frame : frames) {
    py::list parts;
    for (auto& positions : frame) {
      py::array_t<float> a({py::ssize_t(positions.size()), py::ssize_t(3)});
      if (!positions.empty()) std::memcpy(a.mutable_data(), positions[0].data(), positions.size() * sizeof(Vec3));
      parts.append(std::move(a));
    }
    out.append(std::move(parts));
  }
  return out;
}

void exportFile(PySession& s, const std::string& path) {
  std::filesystem::path p(path);
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  std::string stem = p.stem().string(), format = ext.empty() ? ext : ext.substr(1);
  // NAME.skeleton.json: the plant graph (io/skeleton_writer.h).
  std::string stemExt = std::filesystem::path(stem).extension().string();
  std::transform(stemExt.begin(), stemExt.end(), stemExt.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".json" && stemExt == ".skeleton") {
    stem = std::filesystem::path(stem).stem().string();
    format = "skeleton";
  } else if (ext != ".glb" && ext != ".obj") {
    throw Error(path, "", "the file's extension says what to write: .skeleton.json, .glb or .obj");
  }
  s.locked([&] {
    std::filesystem::path dir = p.parent_path().empty() ? std::filesystem::path(".") : p.parent_path();
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) throw Error(path, "", fmt::format("directory {} does not exist", dir.string()));
    io::ExportScene written;
    session::writePlantFiles(s.session(), dir, stem, {format}, s.source(), written);
  });
}

std::vector<std::string> presets(const std::string& model) {
  if (!scene::findModelType(model)) {
    std::string names;
    for (const models::ModelType& t : scene::modelTypes()) names += (names.empty() ? "" : ", ") + t.name;
    throw Error("<python>", "model", fmt::format("must be one of {}, got \"{}\"", names, model));
  }
  if (model == "lsystem") return lsystem::builtinGrammarNames();
  if (model == "graph") {
    // Component graphs have no built-ins: the example graphs shipped with Tendril, by path.
    std::vector<std::string> out;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(TENDRIL_EXAMPLES_DIR) / "graphs", ec))
      if (e.path().extension() == ".json") out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
  }
  return models::builtinSpeciesNames(model);
}

}  // namespace

PYBIND11_MODULE(_tendril, m) {
  m.doc() = "Tendril: plants that grow, climb, move in the wind and can be edited while they grow.";
  render::installRendererImpostorBaker();  // output.impostor in Session.export

  gErrorType = PyErr_NewExceptionWithDoc(
      "tendril.Error",
      "Bad input: a file, a scene or plant dict, an edit, an argument. str(e) is the one-line message "
      "'source:location: message'; e.source, e.location and e.message hold its parts.",
      PyExc_Exception, nullptr);
  m.attr("Error") = py::handle(gErrorType);
  gWarningType = PyErr_NewExceptionWithDoc(
      "tendril.TendrilWarning",
      "What Tendril warns about while it opens, grows or exports (a plant that reached its cap, an "
      "obstacle mesh that is not closed, ...). Session.warnings keeps them too.",
      PyExc_UserWarning, nullptr);
  m.attr("TendrilWarning") = py::handle(gWarningType);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      py::object err = py::reinterpret_borrow<py::object>(gErrorType)(e.what());
      err.attr("source") = e.source();
      err.attr("location") = e.location();
      err.attr("message") = e.message();
      PyErr_SetObject(gErrorType, err.ptr());
    }
  });

  m.def("version", [] { return std::string(TENDRIL_VERSION); }, "Tendril's version.");
  m.def("set_threads", [](int n) {
    if (n < 0) throw Error("<python>", "threads", fmt::format("must be >= 0, got {}", n));
    setThreadCount(n);
  }, py::arg("threads"), "Limits the worker threads (0 = all cores). Results never depend on it.");
  m.def("threads", &threadCount, "The current worker thread limit.");
  m.def("models", [] {
    std::vector<std::string> out;
    for (const models::ModelType& t : scene::modelTypes()) out.push_back(t.name);
    return out;
  }, "The plant models: the values of a plant's \"model\".");
  m.def("presets", &presets, py::arg("model"),
        "Built-in presets of a model: species names (climb, particles), grammar names (lsystem), "
        "example graph files (graph).");

  py::class_<PyPlant, std::shared_ptr<PyPlant>>(m, "Plant",
      "A snapshot of one plant's skeleton and leaves (Tendril's frame: y up, metres). The arrays are "
      "read-only views of the snapshot.")
      .def_property_readonly("name", [](const PyPlant& p) { return p.model.name; })
      .def_property_readonly("model", [](const PyPlant& p) { return p.modelType; })
      .def_property_readonly("node_count", [](const PyPlant& p) { return p.model.nodeCount(); })
      .def_property_readonly("leaf_count", [](const PyPlant& p) { return p.model.leafNode.size(); })
      .def_property_readonly("positions", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(floats(p.position), p.position.size(), 3, self);
      }, "(n, 3) float32: each segment's start")
      .def_property_readonly("orientations", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(floats(p.orientation), p.orientation.size(), 4, self);
      }, "(n, 4) float32: each segment's frame as a quaternion x, y, z, w (its +y is the segment's direction)")
      .def_property_readonly("lengths", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(p.length.data(), p.length.size(), 1, self);
      }, "(n,) float32, m")
      .def_property_readonly("radii", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(p.radius.data(), p.radius.size(), 1, self);
      }, "(n,) float32, m")
      .def_property_readonly("parents", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(p.parent.data(), p.parent.size(), 1, self);
      }, "(n,) int32: each segment's parent, -1 for a root")
      .def_property_readonly("ages", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(p.age.data(), p.age.size(), 1, self);
      }, "(n,) float32: seconds since each segment was created")
      .def_property_readonly("orders", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(p.order.data(), p.order.size(), 1, self);
      }, "(n,) uint16: branch order (0 the main stem, 1 its laterals, ...)")
      .def_property_readonly("flags", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(p.flags.data(), p.flags.size(), 1, self);
      }, "(n,) uint32: node flags (plant/plant_model.h NodeFlags)")
      .def("tips", [](const PyPlant& p) {
        py::array_t<float> a({py::ssize_t(p.model.nodeCount()), py::ssize_t(3)});
        auto r = a.mutable_unchecked<2>();
        for (size_t i = 0; i < p.model.nodeCount(); ++i) {
          const Vec3 t = p.model.tip(i);
          r(i, 0) = t.x(), r(i, 1) = t.y(), r(i, 2) = t.z();
        }
        return a;
      }, "(n, 3) float32: each segment's end (a new array)")
      .def_property_readonly("leaf_nodes", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(p.leafNode.data(), p.leafNode.size(), 1, self);
      }, "(k,) int32: the segment each leaf hangs from")
      .def_property_readonly("leaf_offsets", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(floats(p.leafOffset), p.leafOffset.size(), 3, self);
      }, "(k, 3) float32: each leaf's position in its segment's frame")
      .def_property_readonly("leaf_rotations", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(floats(p.leafRotation), p.leafRotation.size(), 4, self);
      }, "(k, 4) float32: each leaf's rotation in its segment's frame (x, y, z, w)")
      .def_property_readonly("leaf_sizes", [](py::object self) {
        const auto& p = self.cast<const PyPlant&>().model;
        return view(p.leafSize.data(), p.leafSize.size(), 1, self);
      }, "(k,) float32: blade lengths, m")
      .def("__repr__", [](const PyPlant& p) {
        return fmt::format("<tendril.Plant '{}' ({}): {} segments, {} leaves>", p.model.name, p.modelType,
                           p.model.nodeCount(), p.model.leafNode.size());
      });

  py::class_<PyPart>(m, "Part", "One part of a meshed object: its triangles and material. Arrays are read-only views.")
      .def_property_readonly("name", [](const PyPart& p) { return p.get().name; })
      .def_property_readonly("material", [](const PyPart& p) { return p.get().material; })
      .def_property_readonly("positions", [](py::object self) {
        const TriangleMesh& t = *self.cast<const PyPart&>().get().mesh;
        return view(floats(t.positions), t.positions.size(), 3, self);
      }, "(n, 3) float32")
      .def_property_readonly("normals", [](py::object self) {
        const TriangleMesh& t = *self.cast<const PyPart&>().get().mesh;
        return view(floats(t.normals), t.normals.size(), 3, self);
      }, "(n, 3) float32")
      .def_property_readonly("uvs", [](py::object self) {
        const TriangleMesh& t = *self.cast<const PyPart&>().get().mesh;
        return view(floats(t.uvs), t.uvs.size(), 2, self);
      }, "(n, 2) float32")
      .def_property_readonly("indices", [](py::object self) {
        const TriangleMesh& t = *self.cast<const PyPart&>().get().mesh;
        return view(t.indices.data(), t.indices.size() / 3, 3, self);
      }, "(m, 3) uint32: triangles, counter-clockwise seen from outside")
      .def("__repr__", [](const PyPart& p) {
        return fmt::format("<tendril.Part '{}': {} vertices, {} triangles>", p.get().name, p.get().mesh->vertexCount(),
                           p.get().mesh->triangleCount());
      });

  py::class_<PyModel, std::shared_ptr<PyModel>>(m, "Model",
      "The meshed plants (and obstacles when the scene's output includes them), as written to .glb: "
      "objects made of parts, their materials and images.")
      .def_property_readonly("objects", [](const std::shared_ptr<PyModel>& self) {
        py::list objects;
        for (size_t o = 0; o < self->model.objects.size(); ++o) {
          py::list parts;
          for (size_t p = 0; p < self->model.objects[o].parts.size(); ++p) parts.append(PyPart{self, o, p});
          objects.append(py::make_tuple(self->model.objects[o].name, parts));
        }
        return objects;
      }, "list of (name, [Part, ...])")
      .def_property_readonly("parts", [](const std::shared_ptr<PyModel>& self) {
        py::list parts;
        for (size_t o = 0; o < self->model.objects.size(); ++o)
          for (size_t p = 0; p < self->model.objects[o].parts.size(); ++p) parts.append(PyPart{self, o, p});
        return parts;
      }, "every object's parts in order (the order of Session.wind_frames)")
      .def_property_readonly("materials", [](const std::shared_ptr<PyModel>& self) {
        py::list out;
        for (const io::ExportMaterial& mat : self->model.materials) {
          py::dict d;
          d["kind"] = materialKind(mat.kind);
          d["name"] = mat.name;
          d["base_color"] = py::make_tuple(mat.baseColor.x(), mat.baseColor.y(), mat.baseColor.z(), mat.baseColor.w());
          d["roughness"] = mat.roughness;
          d["metallic"] = mat.metallic;
          d["alpha_mask"] = mat.alphaMask;
          d["double_sided"] = mat.doubleSided;
          d["image"] = mat.texture >= 0 ? self->model.textures.at(size_t(mat.texture)).image : -1;
          d["repeat"] = mat.texture >= 0 ? self->model.textures.at(size_t(mat.texture)).repeat : false;
          out.append(std::move(d));
        }
        return out;
      }, "list of dicts: kind ('bark', 'leaf', 'plain'), name, base_color (linear RGBA), roughness, metallic, "
         "alpha_mask (cut out below alpha 0.5), double_sided, image (index into images or -1), repeat")
      .def_property_readonly("images", [](const std::shared_ptr<PyModel>& self) {
        py::list out;
        for (const io::ExportImage& img : self->model.images) {
          py::dict d;
          d["spec"] = img.spec;
          d["mime_type"] = img.image.mimeType;
          d["data"] = py::bytes(reinterpret_cast<const char*>(img.image.bytes.data()), img.image.bytes.size());
          d["width"] = img.image.width;
          d["height"] = img.image.height;
          out.append(std::move(d));
        }
        return out;
      }, "list of dicts: spec, mime_type ('image/png' or 'image/jpeg'), data (the encoded file), width, height");

  py::class_<PySession>(m, "Session",
      "One open scene: its environment and every plant of every model, with the edits and undo of "
      "the studio. Tendril's frame is y up, metres.")
      .def(py::init(&PySession::fromScene), py::arg("scene"), py::arg("base_dir") = "", py::arg("source") = "<python>",
           "A session from a scene document (a dict as in docs/scene-format.md). base_dir resolves its relative "
           "paths (default: the current directory); source names it in errors.")
      .def_static("open", &PySession::open, py::arg("path"), "Opens a scene file (.json) or a session file (.tses).")
      .def("step", [](PySession& s, int64_t count) {
        if (count < 0 || count > 100'000'000) throw Error("<python>", "count", fmt::format("must be in [0, 1e8], got {}", count));
        s.step(uint32_t(count));
      }, py::arg("count") = 1, "Grows every plant `count` steps.")
      .def("run", &PySession::run, py::arg("steps") = py::none(), py::arg("progress") = py::none(),
           "Grows up to `steps` steps (default: the scene's \"steps\"), stopping early when nothing grows any "
           "more, as `tendril grow` does; progress(done) is called after each step. Returns the steps run.")
      .def_property_readonly("step_count", [](PySession& s) { return s.locked([&] { return s.session().stepCount(); }); })
      .def_property_readonly("finished", [](PySession& s) { return s.locked([&] { return s.session().finished(); }); })
      .def_property_readonly("plant_count", [](PySession& s) { return s.locked([&] { return s.session().plantCount(); }); })
      .def_property_readonly("segment_count", [](PySession& s) { return s.locked([&] { return s.session().segmentCount(); }); })
      .def_property_readonly("obstacle_count", [](PySession& s) {
        return s.locked([&] { return size_t(s.session().environment().obstacleCount()); });
      })
      .def_property_readonly("scene", [](PySession& s) {
        Json doc = s.locked([&] { return s.session().sceneDocument(); });
        return fromJson(doc);
      }, "The scene document the session was opened from (a dict).")
      .def_property_readonly("warnings", [](PySession& s) { return s.warnings(); },
                             "Every warning Tendril gave for this session so far (also issued as "
                             "tendril.TendrilWarning).")
      .def("growth_problems", [](PySession& s) {
        const auto found = s.locked([&] { return s.session().diagnoseGrowth(); });
        py::list out;
        for (const session::Session::GrowthReport& r : found) {
          py::dict d;
          d["plant"] = r.plant;
          d["cause"] = models::causeName(r.problem.cause);
          d["stopped"] = r.problem.stopped;
          d["message"] = r.problem.message;
          out.append(d);
        }
        return out;
      }, "Plants that stopped growing in their first steps or stay far below their species' size, and why: "
         "dicts of plant (index), cause (\"seed-blocked\", \"no-support\", \"no-light\", \"crowded\", \"cap\", ...), "
         "stopped (else still growing, small) and message (docs/diagnostics.md). [] when every plant grows as its "
         "species does.")
      .def_property_readonly("state_hash", [](PySession& s) { return s.locked([&] { return s.session().stateHash(); }); },
                             "Hash of every plant and the environment's editable state.")
      .def("add_plant", [](PySession& s, const py::dict& plant) {
        const Json j = toJson(plant, "");
        return s.locked([&] {
          // Errors name the plant's place in the session's scene, as the scene reader does.
          const size_t index = s.session().plantCount();
          try {
            return s.session().addPlant(j, "<python>");
          } catch (const Error& e) {
            if (e.source() != "<python>") throw;
            throw Error(s.source(), fmt::format("/plants/{}{}", index, e.location()), e.message());
          }
        });
      }, py::arg("plant"),
         "Adds a plant now from a scene-file plant object (model, species name or dict, grammar, graph, position, "
         "...). Returns its index.")
      .def("plant", [](PySession& s, int64_t index) {
        auto p = std::make_shared<PyPlant>();
        s.locked([&] {
          const session::Session& session = s.session();
          if (index < 0 || size_t(index) >= session.plantCount())
            throw Error("<python>", "plant", fmt::format("there is no plant {} (the session has {})", index, session.plantCount()));
          // As exported: Session::plants() (stems kept off their supports).
          p->model = std::move(session.plants()[size_t(index)]);
          p->modelType = session.plantSpec(size_t(index)).model;
        });
        return p;
      }, py::arg("index"), "A snapshot of plant `index` (its skeleton and leaves).")
      .def("plant_description", [](PySession& s, int64_t index) {
        Json d = s.locked([&] {
          if (index < 0 || size_t(index) >= s.session().plantCount())
            throw Error("<python>", "plant", fmt::format("there is no plant {} (the session has {})", index, s.session().plantCount()));
          return s.session().plantDescription(size_t(index));
        });
        return fromJson(d);
      }, py::arg("index"), "The plant's scene-file object (None for plants added from code).")
      .def("edit", [](PySession& s, const py::dict& edit) {
        const session::Edit e = readEditDict(edit);
        s.locked([&] { s.editor().apply(e); });
      }, py::arg("edit"),
         "Applies an edit: any object of the edit-script language (docs/edit-scripts.md), e.g. "
         "{'edit': 'cut', 'plant': 0, 'node': 12}. It can be undone.")
      // As edits, so that the journal replays them.
      .def("undo", [](PySession& s) { s.locked([&] { s.editor().apply(session::Undo{}); }); },
           "Undoes the last edit (and the steps grown since); an Error when there is nothing to undo.")
      .def("redo", [](PySession& s) { s.locked([&] { s.editor().apply(session::Redo{}); }); },
           "Redoes the last undone edit; an Error when there is nothing to redo.")
      .def_property_readonly("can_undo", [](PySession& s) { return s.locked([&] { return s.editor().canUndo(); }); })
      .def_property_readonly("can_redo", [](PySession& s) { return s.locked([&] { return s.editor().canRedo(); }); })
      .def("journal", [](PySession& s) {
        Json j = s.locked([&] { return session::editScriptToJson(s.editor().journal()); });
        return fromJson(j);
      }, "Every edit applied, as an edit script (a dict `tendril edit` replays).")
      .def("run_script", [](PySession& s, const py::object& script, int64_t steps) {
        session::EditScript es;
        if (py::isinstance<py::dict>(script)) {
          const Json j = toJson(script, "");
          es = session::parseEditScript(j, "<python>");
        } else {
          const std::string path = py::str(script);
          py::gil_scoped_release release;
          es = session::loadEditScript(path);
        }
        if (steps < 0) throw Error("<python>", "steps", fmt::format("must be >= 0, got {}", steps));
        s.locked([&] { session::runEditScript(s.editor(), es, uint32_t(steps)); });
      }, py::arg("script"), py::arg("steps") = 0,
         "Replays an edit script (a dict or a file path) from now; then steps until `steps` steps have run.")
      .def("mesh", &meshSession, "Meshes every plant with the scene's output settings (a Model).")
      .def("wind_frames", &windFrames, py::arg("seconds") = 4.0f, py::arg("fps") = 24, py::arg("wind") = py::none(),
           "The plants moving in the scene's wind (Growth-Flow motion), as the looping clip of `tendril grow "
           "--wind-animation`: for each of seconds × fps frames, the posed positions of every part of mesh(), in "
           "Model.parts order ((n, 3) float32 arrays with the same vertices as at rest). `wind`, a scene's wind "
           "object (constant or gusty), moves the plants as grown in another wind than the scene's.")
      .def("export", &exportFile, py::arg("path"),
           "Writes the plants as .glb or .obj, or their skeletons as .skeleton.json (by the extension), byte for "
           "byte what `tendril grow` writes.")
      .def("render", [](PySession& s, const std::string& path, int width, int height) {
        if (width < 16 || width > 8192 || height < 16 || height > 8192)
          throw Error(path, "", fmt::format("the picture must be 16 to 8192 pixels on a side, got {} x {}", width, height));
        s.locked([&] { render::writePreview(s.session(), path, width, height); });
      }, py::arg("path"), py::arg("width") = 960, py::arg("height") = 540,
         "Renders the session from the default 3/4 view with Tendril's renderer (headless OpenGL) to a PNG.")
      .def("save", [](PySession& s, const std::string& path) {
        s.locked([&] { session::saveSession(path, s.session(), s.editor().journal()); });
      }, py::arg("path"), "Writes a session file (.tses) that Session.open and the studio continue exactly.")
      .def("save_state", [](PySession& s) {
        std::vector<uint8_t> bytes = s.locked([&] { return s.session().saveState(); });
        return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
      }, "Everything that decides future steps, as bytes.")
      .def("load_state", [](PySession& s, const py::bytes& state) {
        const std::string bytes = state;
        s.locked([&] {
          s.session().loadState({reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()}, "<python>");
        });
      }, py::arg("state"), "Restores a state from save_state(); stepping on gives the same results bit for bit.")
      .def("__repr__", [](PySession& s) {
        return s.locked([&] {
          return fmt::format("<tendril.Session '{}': {} plants, {} segments, step {}>", s.source(), s.session().plantCount(),
                             s.session().segmentCount(), s.session().stepCount());
        });
      });
}
