"""Bought parts as envelopes with their mounting features, one module per part family.

Every number is read from the rig description (``parts.<id>``), which keeps its source and
confidence; :func:`.base.provenance` lists them.
"""
