"""Writes the generated pages of the user guide while mkdocs builds (the mkdocs-gen-files plugin runs it):
the scenario reference, the material library and the examples gallery (see ``reference.py``)."""
import sys
from pathlib import Path

import mkdocs_gen_files

sys.path.insert(0, str(Path(__file__).parent))
import reference  # noqa: E402  (beside this script, not an installed module)

PAGES = {
    "reference/scenario.md": reference.scenario_reference,
    "reference/materials.md": reference.materials_reference,
    "examples.md": reference.examples_gallery,
}

for page, make in PAGES.items():
    with mkdocs_gen_files.open(page, "w") as f:
        f.write(make())
