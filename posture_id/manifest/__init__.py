"""A study from its manifest: trials of several subjects in several conditions, read, their
FRFs, each subject's joint fit and paired tests between the conditions."""

from posture_id.manifest.reading import StudyManifest, TrialEntry, read_manifest
from posture_id.manifest.run import StudyOptions, StudyResult, run_study

__all__ = ["StudyManifest", "TrialEntry", "read_manifest", "StudyOptions", "StudyResult",
           "run_study"]
