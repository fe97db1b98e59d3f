//! What silrig ships to fly without anything of the user's: [`f16_plant`], the Stevens & Lewis F-16 as a plant
//! model, and [`attitude_law`], the paper's adaptive SMC/RBF law as its controller; [`quad_plant`], the X
//! quadrotor (`[plant] model = "quad"`), and [`quad_law`], our cascaded attitude and rate controller for it.

pub mod attitude_law;
pub mod f16_plant;
pub mod quad_law;
pub mod quad_plant;
