//! The linearized equations and their stability: published figures, closed
//! forms, constraint solving and the fast upright path.

mod basu_mandal;
mod benchmark;
mod constraints;
mod fast_path;
mod free_speed;
mod frequency_response;
mod leaning_rider;
mod library_jobs;
mod moore_rider_lean;
mod real_designs;
mod sensitivity;
