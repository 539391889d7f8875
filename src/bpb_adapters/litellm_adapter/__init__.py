"""The litellm adapter: any provider litellm supports, as ``litellm:<model>``.

This package is the only code in bpb that imports litellm, and it does so only when an adapter is
built, so ``bpb --help`` and offline runs never pay for the import.
"""
