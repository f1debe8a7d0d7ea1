"""``calibrate thermal``: the pipeline from images to a judged lens (:mod:`.pipeline`) and every file it
writes (:mod:`.outputs`)."""
