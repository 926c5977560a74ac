// Where a server error points in the scene's JSON (docs/serve_api.md: an error answer
// carries "json_path", e.g. "elements[2].path[1]"): the character range of that value in
// the text of the scene editor, so the page can select it. Pure: tested in
// test/error_place.test.ts.

interface Step {
  key?: string;
  index?: number;
}

// "a.b[2].c" → steps; undefined for a path the server would not write.
function splitPath(path: string): Step[] | undefined {
  const steps: Step[] = [];
  const re = /([^.[\]]+)|\[(\d+)\]/g;
  let consumed = 0;
  for (let m = re.exec(path); m; m = re.exec(path)) {
    if (m.index !== consumed && !(path[consumed] === "." && m.index === consumed + 1)) return undefined;
    steps.push(m[1] !== undefined ? { key: m[1] } : { index: Number(m[2]) });
    consumed = m.index + m[0].length;
  }
  return consumed === path.length ? steps : undefined;
}

function skipSpace(t: string, i: number): number {
  while (i < t.length && " \t\r\n".includes(t[i])) ++i;
  return i;
}

// From an opening quote to the index after the closing one.
function skipString(t: string, i: number): number {
  for (++i; i < t.length; ++i) {
    if (t[i] === "\\") ++i;
    else if (t[i] === '"') return i + 1;
  }
  return t.length;
}

function skipValue(t: string, i: number): number {
  if (t[i] === '"') return skipString(t, i);
  if (t[i] === "{" || t[i] === "[") {
    let depth = 0;
    for (; i < t.length; ++i) {
      const c = t[i];
      if (c === '"') i = skipString(t, i) - 1;
      else if (c === "{" || c === "[") ++depth;
      else if ((c === "}" || c === "]") && --depth === 0) return i + 1;
    }
    return i;
  }
  while (i < t.length && !",]} \t\r\n".includes(t[i])) ++i;
  return i;
}

// The [start, end) range of the value at `path` in JSON `text`, or undefined when the
// text has no value there (or is not JSON as far as the path goes).
export function locateJsonPath(text: string, path: string): { start: number; end: number } | undefined {
  const steps = splitPath(path);
  if (!steps) return undefined;
  let i = skipSpace(text, 0);
  for (const step of steps) {
    if (step.key !== undefined && text[i] === "{") {
      i = skipSpace(text, i + 1);
      let found = false;
      while (i < text.length && text[i] === '"') {
        const keyEnd = skipString(text, i);
        let key: string;
        try {
          key = JSON.parse(text.slice(i, keyEnd));
        } catch {
          return undefined;
        }
        i = skipSpace(text, keyEnd);
        if (text[i] !== ":") return undefined;
        i = skipSpace(text, i + 1);
        if (key === step.key) {
          found = true;
          break;
        }
        i = skipSpace(text, skipValue(text, i));
        if (text[i] === ",") i = skipSpace(text, i + 1);
      }
      if (!found) return undefined;
    } else if (step.index !== undefined && text[i] === "[") {
      i = skipSpace(text, i + 1);
      for (let k = 0; k < step.index; ++k) {
        if (i >= text.length || text[i] === "]") return undefined;
        i = skipSpace(text, skipValue(text, i));
        if (text[i] === ",") i = skipSpace(text, i + 1);
      }
      if (i >= text.length || text[i] === "]") return undefined;
    } else {
      return undefined;
    }
  }
  if (i >= text.length) return undefined;
  return { start: i, end: skipValue(text, i) };
}
