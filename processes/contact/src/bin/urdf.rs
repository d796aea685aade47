//! `caravan-contact-urdf`: writes the scenario's arm (`launch/contact/robots/arm.urdf`) from
//! its geometry, so the URDF and the Monte-Carlo's arm cannot drift apart (a test checks).
//!
//!   caravan-contact-urdf > launch/contact/robots/arm.urdf

fn main() {
    print!(
        "{}",
        caravan_contact::arm_urdf::urdf(&caravan_contact::monte_carlo::reference_arm())
    );
}
