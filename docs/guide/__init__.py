"""The assembly guide generator: docs/assembly/steps.yaml checked against the CAD assembly and the BOM
(:mod:`.steps`), rendered with a picture per step (:mod:`.pictures`), the wiring diagram (:mod:`.wiring`)
and the BOM into a small site (:mod:`.site`); `python cad/build.py docs` (:mod:`.cli`). Templates beside it."""
