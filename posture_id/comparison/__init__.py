"""Two models fitted to one recording (or a cohort) and which its sway supports."""
