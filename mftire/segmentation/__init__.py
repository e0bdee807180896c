"""Segmentation and sweep analysis: from rows in measurement order to labelled sweeps."""
