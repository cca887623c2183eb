#include "io/pbrt/pbrt_loader.h"

#include <filesystem>

#include "io/input_file.h"
#include "io/pbrt/scene_converter.h"

namespace caustica {

namespace {

void convert(const std::string& text, const std::string& name, SceneBuilder& builder,
             pbrt::LoaderContext& ctx, const pbrt::ParseOptions& options) {
  pbrt::Tokenizer tokens(text, name);
  pbrt::SceneConverter converter(builder, ctx);
  pbrt::parse_directives(tokens, converter, options);
  converter.finish();
}

}  // namespace

std::unique_ptr<Scene> load_pbrt(const std::string& path, WarningSink warn) {
  std::string text;
  try {
    text = read_input_file(path);
  } catch (const std::runtime_error& e) {
    throw SceneLoadError({path, 0, 0}, std::string("cannot open the scene file: ") + e.what());
  }
  pbrt::LoaderContext ctx(warn);
  ctx.main_directory = std::filesystem::path(path).parent_path().string();
  pbrt::ParseOptions options;
  options.read_file = read_input_file;
  SceneBuilder builder;
  convert(text, path, builder, ctx, options);
  return builder.build(std::filesystem::path(path).stem().string());
}

void parse_pbrt_string(const std::string& text, const std::string& name, SceneBuilder& builder,
                       WarningSink warn, size_t max_triangles) {
  pbrt::LoaderContext ctx(warn);
  ctx.allow_files = false;
  ctx.max_triangles = max_triangles;
  convert(text, name, builder, ctx, pbrt::ParseOptions{});
}

std::unique_ptr<Scene> load_pbrt_string(const std::string& text, WarningSink warn,
                                        const std::string& name) {
  SceneBuilder builder;
  parse_pbrt_string(text, name, builder, warn);
  return builder.build(name);
}

}  // namespace caustica
