#include "io/pbrt/pbrt_loader.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/pbrt/scene_converter.h"

namespace caustica {

namespace {

std::optional<std::string> read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void convert(const std::string& text, const std::string& name, SceneBuilder& builder,
             pbrt::LoaderContext& ctx, const pbrt::ParseOptions& options) {
  pbrt::Tokenizer tokens(text, name);
  pbrt::SceneConverter converter(builder, ctx);
  pbrt::parse_directives(tokens, converter, options);
  converter.finish();
}

}  // namespace

std::unique_ptr<Scene> load_pbrt(const std::string& path, WarningSink warn) {
  std::optional<std::string> text = read_text_file(path);
  if (!text) throw SceneLoadError({path, 0, 0}, "cannot open the scene file");
  pbrt::LoaderContext ctx(warn);
  ctx.main_directory = std::filesystem::path(path).parent_path().string();
  pbrt::ParseOptions options;
  options.read_file = read_text_file;
  SceneBuilder builder;
  convert(*text, path, builder, ctx, options);
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
