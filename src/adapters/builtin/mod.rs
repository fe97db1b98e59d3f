//! What silrig ships to fly without anything of the user's: [`f16_plant`], the Stevens & Lewis F-16 as a plant
//! model, and [`attitude_law`], the paper's adaptive SMC/RBF law as a controller.

pub mod attitude_law;
pub mod f16_plant;
