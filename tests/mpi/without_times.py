"""Prints a JSON or CSV file without its wall-clock times (keys / columns ending in _ms), the
rest verbatim, so that two runs of one computation compare byte for byte."""
import json
import sys

path = sys.argv[1]
text = open(path).read()
if path.endswith(".json"):
    def strip(v):
        if isinstance(v, dict):
            return {k: strip(x) for k, x in v.items() if not k.endswith("_ms")}
        if isinstance(v, list):
            return [strip(x) for x in v]
        return v
    # Numbers stay as written (parse_float=str): no rounding hides a difference.
    print(json.dumps(strip(json.loads(text, parse_float=str)), indent=1))
else:
    rows = [line.split(",") for line in text.splitlines()]
    keep = [i for i, name in enumerate(rows[0]) if not name.endswith("_ms")] if rows else []
    for r in rows:
        print(",".join(r[i] for i in keep))
