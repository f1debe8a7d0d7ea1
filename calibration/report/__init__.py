"""The calibration report: what the data covers, how uncertain the solved lens is, and a verdict
(:mod:`.analysis`, :mod:`.verdict`), drawn as inline SVG (:mod:`.svg`) into report.html (:mod:`.html`);
why images gave no board (:mod:`.missed`) and what 8-bit input costs (:mod:`.input_depth`)."""
