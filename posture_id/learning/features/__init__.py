"""What networks see of a sway: the paper's spectrogram images (:mod:`.spectrograms`), a
sway's stimulus-locked harmonics (:mod:`.harmonics`) and the universal network's module
FRFs made of them (:mod:`.module_frfs`)."""
