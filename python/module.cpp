// The `caustica` Python module: scenes, images and metrics here, rendering in render.cpp.
#include <pybind11/stl.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <vector>

#include "bindings.h"
#include "image/image_io.h"
#include "image/metrics.h"
#include "image/tonemap.h"
#include "io/builtin_scenes.h"
#include "io/scene_loader.h"
#include "preflight.h"

namespace caustica::python {

namespace {

// Raised for every scene input problem; a ValueError, so `except ValueError` also catches it.
struct LoadErrorTag {};
py::handle load_error_type;

[[noreturn]] void raise_load_error(const std::string& message, const SourceLocation* where) {
  py::object error = py::reinterpret_borrow<py::object>(load_error_type)(message);
  // The location as attributes too, for a notebook that points at the offending line.
  error.attr("file") = where ? py::cast(where->file) : py::none();
  error.attr("line") = where && where->line > 0 ? py::cast(where->line) : py::none();
  error.attr("column") = where && where->line > 0 ? py::cast(where->column) : py::none();
  PyErr_SetObject(load_error_type.ptr(), error.ptr());
  throw py::error_already_set();
}

// Loader warnings arrive through a plain function pointer while the GIL is released; they are
// collected here (loading runs on the calling thread) and issued as Python warnings afterwards.
thread_local std::vector<std::string>* pending_warnings = nullptr;
void collect_warning(const std::string& message) {
  if (pending_warnings) pending_warnings->push_back(message);
}

std::shared_ptr<LoadedScene> load(const std::string& name_or_path, const py::object& resolution,
                                  const py::object& max_depth, const py::object& camera) {
  auto loaded = std::make_shared<LoadedScene>();
  loaded->name_or_path = name_or_path;
  LoadOptions options;
  options.warn = collect_warning;
  if (!camera.is_none()) options.camera_index = int(integer_arg("camera", camera, 0, INT_MAX));
  // Light vertices store their depth in 8 bits, hence 255 (as --max-depth).
  if (!max_depth.is_none()) loaded->max_depth = int(integer_arg("max_depth", max_depth, 0, 255));
  int width = 0, height = 0;
  if (!resolution.is_none()) {
    if (!py::isinstance<py::sequence>(resolution) || py::isinstance<py::str>(resolution) ||
        py::len(resolution) != 2)
      throw py::type_error("resolution must be a (width, height) pair");
    const py::sequence wh = resolution.cast<py::sequence>();
    width = int(integer_arg("resolution width", wh[0], 1, INT_MAX));
    height = int(integer_arg("resolution height", wh[1], 1, INT_MAX));
    if (std::string problem = cli::film_memory_problem(width, height, 0); !problem.empty())
      throw py::value_error(problem);
  }
  if (std::string problem = cli::scene_path_problem(name_or_path); !problem.empty())
    raise_load_error(problem, nullptr);

  std::vector<std::string> warnings;
  std::string error;
  std::optional<SourceLocation> error_where;
  {
    py::gil_scoped_release release;  // a large scene takes a while; other threads may run
    pending_warnings = &warnings;
    try {
      loaded->scene = load_scene(name_or_path, options);
    } catch (const SceneLoadError& e) {
      error = e.what();
      error_where = e.where();
    } catch (const std::runtime_error& e) {  // UnknownSceneError and the loaders' other failures
      error = e.what();
    }
    pending_warnings = nullptr;
  }
  for (const std::string& w : warnings)
    if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) != 0)
      throw py::error_already_set();  // warnings turned into errors (-W error)
  if (!loaded->scene) raise_load_error(error, error_where ? &*error_where : nullptr);

  Scene& scene = *loaded->scene;
  if (width > 0) scene.override_resolution(width, height);
  // The scene file's own resolution has not been checked yet.
  if (std::string problem =
          cli::film_memory_problem(scene.camera().width(), scene.camera().height(), 0);
      !problem.empty())
    raise_load_error(problem, nullptr);
  return loaded;
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

void write(const std::string& path, const py::handle& image, const py::handle& exposure) {
  const std::string ext = lower_extension(path);
  if (ext != ".exr" && ext != ".png" && ext != ".pfm")
    throw py::value_error("cannot tell the format of '" + path + "': use .exr, .png or .pfm");
  const Image img = to_image(image, "image");
  const float stops = float(number_arg("exposure", exposure, -64, 64, false));
  py::gil_scoped_release release;
  if (ext == ".exr")
    write_exr(img, path);
  else if (ext == ".png")
    write_png_srgb(tonemap_srgb(img, stops), path);
  else
    write_pfm(img, path);
}

py::array_t<float> read(const std::string& path, bool srgb) {
  Image img;
  {
    py::gil_scoped_release release;
    img = read_image(path, srgb);
  }
  return to_array(img);
}

// Metrics take (image, reference): relMSE normalises by the reference.
template <double (*metric)(const Image&, const Image&)>
double metric_of(const py::handle& image, const py::handle& reference) {
  const Image img = to_image(image, "image"), ref = to_image(reference, "reference");
  py::gil_scoped_release release;
  return metric(img, ref);  // std::invalid_argument (sizes differ) becomes ValueError
}

double relmse(const py::handle& image, const py::handle& reference, const py::handle& eps) {
  const Image img = to_image(image, "image"), ref = to_image(reference, "reference");
  const double e = number_arg("eps", eps, 0, 1e30, true);
  py::gil_scoped_release release;
  return rel_mse(img, ref, e);
}

}  // namespace

py::array_t<float> to_array(const Image& image) {
  static_assert(sizeof(Rgb) == 3 * sizeof(float), "Image pixels are packed float triples");
  py::array_t<float> out({py::ssize_t(image.height()), py::ssize_t(image.width()), py::ssize_t(3)});
  if (image.pixel_count() > 0)
    std::memcpy(out.mutable_data(), image.pixels().data(), image.pixel_count() * sizeof(Rgb));
  return out;
}

Image to_image(const py::handle& value, const std::string& what) {
  using Array = py::array_t<float, py::array::c_style | py::array::forcecast>;
  Array array = Array::ensure(value);
  if (!array) {
    PyErr_Clear();
    throw py::type_error(what + " must be an array of shape (height, width, 3)");
  }
  if (array.ndim() != 3 || array.shape(2) != 3 || array.shape(0) < 1 || array.shape(1) < 1 ||
      array.shape(0) > INT_MAX || array.shape(1) > INT_MAX) {
    std::string shape;
    for (py::ssize_t i = 0; i < array.ndim(); ++i)
      shape += (i ? ", " : "") + std::to_string(array.shape(i));
    throw py::value_error(what + " must have shape (height, width, 3), got (" + shape + ")");
  }
  Image image(int(array.shape(1)), int(array.shape(0)));
  const float* v = array.data();
  for (size_t i = 0; i < image.pixel_count(); ++i)
    image[i] = Rgb(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
  return image;
}

int64_t integer_arg(const std::string& name, const py::handle& value, int64_t lo, int64_t hi) {
  // bool is an int subclass in Python, but True as a sample count is a mistake.
  if (PyBool_Check(value.ptr()) || !PyLong_Check(value.ptr()))
    throw py::type_error(name + " must be an int, got " +
                         std::string(py::str(value.get_type().attr("__name__"))));
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
  if (overflow != 0 || v < lo || v > hi)
    throw py::value_error(name + " must be an integer from " + std::to_string(lo) + " to " +
                          std::to_string(hi) + ", got " + std::string(py::repr(value)));
  return v;
}

uint64_t unsigned_arg(const std::string& name, const py::handle& value, uint64_t lo, uint64_t hi) {
  if (PyBool_Check(value.ptr()) || !PyLong_Check(value.ptr()))
    throw py::type_error(name + " must be an int, got " +
                         std::string(py::str(value.get_type().attr("__name__"))));
  // Negative or above 2^64-1: Python's own conversion fails and says why; ours names the value.
  const unsigned long long v = PyLong_AsUnsignedLongLong(value.ptr());
  const bool failed = v == static_cast<unsigned long long>(-1) && PyErr_Occurred();
  if (failed) PyErr_Clear();
  if (failed || v < lo || v > hi)
    throw py::value_error(name + " must be an integer from " + std::to_string(lo) + " to " +
                          std::to_string(hi) + ", got " + std::string(py::repr(value)));
  return v;
}

double number_arg(const std::string& name, const py::handle& value, double lo, double hi,
                  bool lo_open) {
  if (PyBool_Check(value.ptr()) || !(PyLong_Check(value.ptr()) || PyFloat_Check(value.ptr())))
    throw py::type_error(name + " must be a number, got " +
                         std::string(py::str(value.get_type().attr("__name__"))));
  const double v = PyFloat_AsDouble(value.ptr());  // an int beyond a double's range: inf
  if (v == -1.0 && PyErr_Occurred()) PyErr_Clear();
  // NaN compares false, so it fails the range test as the command line's does.
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  if (!ok) {
    char range[96];
    std::snprintf(range, sizeof range, "%s %.10g and at most %.10g",
                  lo_open ? "greater than" : "at least", lo, hi);
    throw py::value_error(name + " must be a number " + range + ", got " +
                          std::string(py::repr(value)));
  }
  return v;
}

}  // namespace caustica::python

namespace cp = caustica::python;
namespace py = pybind11;

PYBIND11_MODULE(caustica, m) {
  m.doc() =
      "caustica: load scenes, render them with any of the renderer's integrators, compare the "
      "integrators at equal time and measure errors, from a script or a notebook.\n\n"
      "Images are numpy float32 arrays of shape (height, width, 3), linear Rec.709 RGB, top row "
      "first. Rendering releases the GIL; Ctrl-C stops a render after its current iteration and "
      "raises KeyboardInterrupt. See docs/python.md.";

  static py::exception<cp::LoadErrorTag> load_error(m, "LoadError", PyExc_ValueError);
  cp::load_error_type = load_error;
  load_error.doc() =
      "A scene that cannot be loaded: unknown name, missing or unreadable file, malformed input. "
      "The message starts with file:line:col where the input is at fault; the attributes file, "
      "line and column carry the same (None where unknown).";

  py::class_<cp::LoadedScene, std::shared_ptr<cp::LoadedScene>>(
      m, "Scene", "A loaded scene, immutable; made by caustica.load().")
      .def_property_readonly(
          "name", [](const cp::LoadedScene& s) { return s.name_or_path; },
          "The built-in name or path it was loaded from.")
      .def_property_readonly(
          "resolution",
          [](const cp::LoadedScene& s) {
            return py::make_tuple(s.scene->camera().width(), s.scene->camera().height());
          },
          "(width, height) of the images it renders.")
      .def_property_readonly(
          "spp",
          [](const cp::LoadedScene& s) -> py::object {
            const int spp = s.scene->settings().spp;
            return spp > 0 ? py::cast(spp) : py::none();
          },
          "Samples per pixel the scene file asks for, or None.")
      .def_property_readonly(
          "max_depth",
          [](const cp::LoadedScene& s) {
            const int scene_depth = s.scene->settings().max_depth;
            return s.max_depth >= 0 ? s.max_depth : (scene_depth > 0 ? scene_depth : 10);
          },
          "Maximum scattering vertices renders use unless render() is given max_depth: load()'s "
          "max_depth, else the scene file's, else 10.")
      .def_property_readonly(
          "integrator",
          [](const cp::LoadedScene& s) -> py::object {
            const std::string& name = s.scene->settings().integrator;
            return name.empty() ? py::none() : py::cast(name);
          },
          "The integrator the scene file names (mapped to caustica's names), or None.")
      .def("__repr__", [](const cp::LoadedScene& s) {
        return "<caustica.Scene '" + s.name_or_path + "' " +
               std::to_string(s.scene->camera().width()) + "x" +
               std::to_string(s.scene->camera().height()) + ">";
      });

  m.def("load", &cp::load, py::arg("name_or_path"), py::arg("resolution") = py::none(),
        py::arg("max_depth") = py::none(), py::arg("camera") = py::none(),
        "load(name_or_path, resolution=None, max_depth=None, camera=None) -> Scene\n\n"
        "Loads a built-in scene by name (see scenes()), a pbrt-v4 file (.pbrt) or a glTF 2.0 file "
        "(.gltf/.glb).\n"
        "resolution: (width, height) overriding the scene's film.\n"
        "max_depth: maximum scattering vertices, 0..255 (pbrt-v4's maxdepth; 1 = direct light); "
        "default: the scene file's, else 10.\n"
        "camera: glTF camera index in node order (default: the first).\n"
        "Raises LoadError (a ValueError) for scene input problems, with file:line:col in the "
        "message; loader warnings become UserWarning.");

  m.def(
      "scenes",
      [] {
        py::list out;
        for (const auto& s : caustica::builtin_scenes())
          out.append(py::make_tuple(s.name, s.description));
        return out;
      },
      "scenes() -> list of (name, description) of the built-in scenes.");

  m.def("write", &cp::write, py::arg("path"), py::arg("image"), py::arg("exposure") = 0.0,
        "write(path, image, exposure=0.0)\n\n"
        "Writes an image by the path's extension: .exr (linear float, never tone mapped), .png "
        "(8-bit sRGB after exposure in stops, -64..64, and clamping, as the command line's PNG) "
        "or .pfm. Goes through a temporary file and a rename.");
  m.def("read", &cp::read, py::arg("path"), py::arg("srgb") = true,
        "read(path, srgb=True) -> numpy.ndarray float32 (height, width, 3)\n\n"
        "Reads EXR or PFM (linear) or PNG/JPEG/TGA/BMP/HDR; 8-bit formats are decoded from sRGB "
        "to linear unless srgb is False. Raises RuntimeError naming the file when it cannot.");

  py::module_ metrics = m.def_submodule(
      "metrics",
      "Error metrics of an image against a reference, as caustica compare reports them: over "
      "every pixel and channel, in double precision. Sizes must match (else ValueError).");
  metrics.def("mse", &cp::metric_of<caustica::mse>, py::arg("image"), py::arg("reference"),
              "mse(image, reference) -> float: mean of (image - reference)^2.");
  metrics.def("relmse", &cp::relmse, py::arg("image"), py::arg("reference"), py::arg("eps") = 0.01,
              "relmse(image, reference, eps=0.01) -> float: mean of (image - reference)^2 / "
              "(reference^2 + eps), each channel normalised by its own reference value.");
  metrics.def("ssim", &cp::metric_of<caustica::ssim>, py::arg("image"), py::arg("reference"),
              "ssim(image, reference) -> float: mean SSIM of the tone-mapped luminance (11x11 "
              "Gaussian window, sigma 1.5); 1 for identical images.");

  cp::add_render_functions(m);
}
