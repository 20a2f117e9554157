//! Measuring and showing models: the paper's experiment (tables against baselines), accuracy
//! measures, renders and plots, the documents built from them (`aprt demo`'s report and
//! `aprt results`), and the accuracy-against-cost sweep of `aprt report`.

pub mod demo;
pub mod evaluate;
pub mod experiment;
pub mod figures;
pub mod irradiance_rig_frame;
pub mod irradiance_rig_study;
pub mod lightmap_preview;
pub mod lightmap_study;
pub mod plots;
pub mod render;
pub mod results;
pub mod sweep;
pub mod web;
