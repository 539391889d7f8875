"""Datasets: generate one with a scene family (:func:`generate_dataset`) and read one
(:func:`load_dataset`)."""

from bpb_core.dataset.generate import GenerateProgress, NoProgress, generate_dataset
from bpb_core.dataset.reader import Dataset, load_dataset

__all__ = ["Dataset", "GenerateProgress", "NoProgress", "generate_dataset", "load_dataset"]
