// The paper's colours for singularity types (DESIGN §8, render/texture_animation.h):
// green source, red sink, blue saddle, magenta center and foci.
export const TYPE_COLORS: Record<string, string> = {
  source: "#1fa32e",
  repelling_focus: "#c026d3",
  sink: "#d7261e",
  attracting_focus: "#c026d3",
  saddle: "#1f4fd7",
  center: "#c026d3",
  ccw_center: "#c026d3",
  cw_center: "#c026d3",
};

export function typeColor(type: string): string {
  return TYPE_COLORS[type] ?? "#555555";
}

export const BIFURCATION_COLOR = "#f59e0b";
export const PATHLINE_COLOR = "#0d9488";
export const STREAMLINE_COLOR = "#2563eb";
export const STREAKLINE_COLOR = "#db2777";  // sketched streaklines (issue 20)
// Where a surface guide went wrong first (the key-frame report's "show where"): a colour
// no singularity type, design curve or bifurcation has.
export const WRONG_PLACE_COLOR = "#06b6d4";
