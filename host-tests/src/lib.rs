//! Host-side tools for pfe: simulator, LMS200 emulator, baselines, evaluation, CLI support.
