"""Task Q3: where is every ball at the horizon (null once pocketed)."""
