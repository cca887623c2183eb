// Parts of the `caustica` Python module shared by its two files: module.cpp (scenes, images,
// metrics) and render.cpp (render, compare, integrators). docs/python.md is the user's guide.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>

#include "image/image.h"
#include "scene/scene.h"

namespace caustica::python {

namespace py = pybind11;

// A loaded scene and what load() was told that render() and compare() apply later, as the
// command line applies its flags after loading.
struct LoadedScene {
  std::string name_or_path;  // as given: compare() reports it as results.json's "scene"
  std::unique_ptr<Scene> scene;
  int max_depth = -1;  // load(max_depth=...); -1: the scene file's, else 10
};

// Images cross the boundary as float32 arrays of shape (height, width, 3), top row first,
// linear RGB: the layout of Image, so the conversion is one copy.
py::array_t<float> to_array(const Image& image);
// Accepts anything NumPy converts to such an array; `what` names the argument in errors.
Image to_image(const py::handle& value, const std::string& what);

// Argument checks with the command line's ranges (apps/caustica/scene_setup.cpp). A wrong type
// raises TypeError, a value out of range ValueError naming the argument.
int64_t integer_arg(const std::string& name, const py::handle& value, int64_t lo, int64_t hi);
uint64_t unsigned_arg(const std::string& name, const py::handle& value, uint64_t lo, uint64_t hi);
double number_arg(const std::string& name, const py::handle& value, double lo, double hi,
                  bool lo_open);

// render(), compare() and integrators().
void add_render_functions(py::module_& m);

}  // namespace caustica::python
