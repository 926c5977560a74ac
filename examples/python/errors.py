"""Bad input: a ValueError whose message is the command line's sentence, and whose
attributes say where the problem is (to point at it in an editor).

    PYTHONPATH=build/release/python python3 examples/python/errors.py
"""
import json
import os
import tempfile

import tvf

scene = {
    "tvf": 1,
    "domain": {"grid": {"size": [33, 33]}},
    "time": {"frames": 10},
    "elements": [{"kind": "singular", "type": "sourse", "path": [[0, 0, 0]]}],
}
with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, "bad.json")
    with open(path, "w") as out:
        json.dump(scene, out, indent=2)
    try:
        tvf.generate(path)
    except ValueError as e:
        print(e)                        # .../bad.json: elements[0].type: unknown singular type "sourse" ...
        print(e.file, e.json_path)      # .../bad.json elements[0].type
        print("line", e.line, "column", e.column)  # where "sourse" is in the file
        line = open(path).read().splitlines()[e.line - 1]
        print(line)
        print(" " * (e.column - 1) + "^")
