#include "tvf/scene/scene.h"

#include <filesystem>
#include <utility>

namespace tvf {
namespace {

// One table per enum: the enum value and its exact name in the scene format (DESIGN §10).
constexpr std::pair<SingularType, const char*> kSingularNames[] = {
    {SingularType::source, "source"},
    {SingularType::sink, "sink"},
    {SingularType::saddle, "saddle"},
    {SingularType::ccw_center, "ccw_center"},
    {SingularType::cw_center, "cw_center"},
    {SingularType::repelling_focus, "repelling_focus"},
    {SingularType::attracting_focus, "attracting_focus"},
};
constexpr std::pair<BifurcationType, const char*> kBifurcationNames[] = {
    {BifurcationType::saddle_source_cancellation, "saddle_source_cancellation"},
    {BifurcationType::saddle_sink_creation, "saddle_sink_creation"},
    {BifurcationType::saddle_source_creation, "saddle_source_creation"},
    {BifurcationType::saddle_sink_cancellation, "saddle_sink_cancellation"},
    {BifurcationType::hopf_supercritical, "hopf_supercritical"},
    {BifurcationType::hopf_subcritical, "hopf_subcritical"},
};
constexpr std::pair<Generator, const char*> kGeneratorNames[] = {
    {Generator::basis, "basis"},
    {Generator::constrained, "constrained"},
    {Generator::spacetime, "spacetime"},
    {Generator::deform, "deform"},
};
constexpr std::pair<Weights, const char*> kWeightNames[] = {
    {Weights::cotan, "cotan"},
    {Weights::uniform, "uniform"},
    {Weights::mean_value, "mean_value"},
};

template <class E, size_t N>
const char* name_of(const std::pair<E, const char*> (&table)[N], E value) {
  for (const auto& [e, name] : table)
    if (e == value) return name;
  return "?";
}

template <class E, size_t N>
std::optional<E> value_of(const std::pair<E, const char*> (&table)[N], const std::string& s) {
  for (const auto& [e, name] : table)
    if (s == name) return e;
  return std::nullopt;
}

}  // namespace

Mat2 jacobian_of(SingularType type) {
  Mat2 j;
  switch (type) {
    case SingularType::source: j << 1, 0, 0, 1; break;
    case SingularType::sink: j << -1, 0, 0, -1; break;
    case SingularType::saddle: j << 1, 0, 0, -1; break;
    case SingularType::ccw_center: j << 0, -1, 1, 0; break;
    case SingularType::cw_center: j << 0, 1, -1, 0; break;
    case SingularType::repelling_focus: j << 1, -1, 1, 1; break;
    case SingularType::attracting_focus: j << -1, -1, 1, -1; break;
  }
  return j;
}

const char* to_string(SingularType t) { return name_of(kSingularNames, t); }
const char* to_string(BifurcationType t) { return name_of(kBifurcationNames, t); }
const char* to_string(Generator g) { return name_of(kGeneratorNames, g); }
const char* to_string(Weights w) { return name_of(kWeightNames, w); }
const char* to_string(SolverMethod m) {
  switch (m) {
    case SolverMethod::automatic: return "auto";
    case SolverMethod::modes: return "modes";
    case SolverMethod::cg: return "cg";
    case SolverMethod::bicgstab: return "bicgstab";
  }
  return "auto";
}
const char* to_string(KeyframeTopology k) { return k == KeyframeTopology::matched ? "matched" : "free"; }

std::optional<SingularType> singular_type_from_string(const std::string& s) {
  return value_of(kSingularNames, s);
}
std::optional<BifurcationType> bifurcation_type_from_string(const std::string& s) {
  return value_of(kBifurcationNames, s);
}
std::optional<Generator> generator_from_string(const std::string& s) {
  return value_of(kGeneratorNames, s);
}
std::optional<Weights> weights_from_string(const std::string& s) {
  return value_of(kWeightNames, s);
}

std::string Scene::resolve_path(const std::string& path) const {
  if (path.empty() || source_path.empty()) return path;
  const std::filesystem::path p(path);
  if (p.is_absolute()) return path;
  const std::filesystem::path folder = std::filesystem::path(source_path).parent_path();
  return folder.empty() ? path : (folder / p).string();
}

std::string Scene::resolved_mesh_path() const { return resolve_path(domain.mesh); }

}  // namespace tvf
