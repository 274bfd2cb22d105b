//! The application loop: driver → pfe-core → framed output.
