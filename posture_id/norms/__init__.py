"""Groups and norms of FRFs (issue 43)."""
