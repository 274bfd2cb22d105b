//! baselines (being written).
