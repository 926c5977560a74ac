#pragma once
// How close a found singularity or bifurcation must lie to a designed one to count as it.
// The design check (design/design_check.h) and the editor's acceptance of an edit
// (edit/field_editor.h) use the same values, so an edit the editor accepts is one the
// design check finds as edited.

namespace tvf {

// In mean edge lengths of the domain: the zero of a sampled field moves by O(h), and the
// neighbouring elements push it a little further.
inline constexpr double kDesignPositionTolerance = 2.5;
// In frame steps, for a bifurcation's time.
inline constexpr double kDesignTimeTolerance = 2.0;

}  // namespace tvf
