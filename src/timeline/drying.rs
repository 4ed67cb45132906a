//! Drying that dries: in a `dry` stage without `drying_time`, the water in
//! the hair evaporates into the air around each vertex, with a time
//! constant (seconds) from the air's temperature, humidity and speed, and
//! the hydrogen bonds re-form by the water that left (wetness 1 to 0 takes
//! the hydrogen rate 0 to 1, (17) remembering the shape the hair dries in).
//! Where the blower's air reaches, its speed and heat fall with the
//! distance from its axis as the blower's push does, paper (19); elsewhere
//! the room air dries the hair slowly.
//!
//! The time constant is that of one fibre of radius `r` in cross flow
//! (docs/model.md, "Drying"):
//!
//! `tau = phi rho_h r^2 / (Sh D (rho_s(T_s) - rho_v))`
//!
//! the water a fibre holds per metre (`phi rho_h pi r^2`) over what leaves
//! it per second (`h_m 2 pi r Delta rho_v`, `h_m = Sh D / 2r`). `Sh` is the
//! Sherwood number of a cylinder in cross flow (Churchill and Bernstein
//! 1977, through the heat and mass transfer analogy), `T_s` the wet fibre's
//! surface temperature, which evaporation cools to the wet-bulb balance
//! (Chilton-Colburn analogy), `rho_s` the saturated vapour density
//! (Magnus form of Alduchov and Eskridge 1996). Wetness falls as
//! `w <- w exp(-dt / tau)`.

use super::schema::StageSpec;
use crate::sim::Blower;

/// Water a saturated hair fibre holds, kg per kg of dry hair (Robbins,
/// "Chemical and Physical Behavior of Human Hair", 5th ed. 2012:
/// about 31 % at 100 % relative humidity).
pub const WATER_UPTAKE: f64 = 0.31;
/// Diffusivity of water vapour in air, m^2/s (Incropera et al.,
/// "Fundamentals of Heat and Mass Transfer", Table A.8: 0.26e-4 at 298 K).
pub const VAPOUR_DIFFUSIVITY: f64 = 2.6e-5;
/// Kinematic viscosity of air, m^2/s (Incropera, Table A.4: 15.89e-6 at
/// 300 K).
pub const AIR_VISCOSITY: f64 = 15.89e-6;
/// Thermal diffusivity of air, m^2/s (Incropera, Table A.4: 22.5e-6 at
/// 300 K).
const AIR_THERMAL_DIFFUSIVITY: f64 = 22.5e-6;
/// Volumetric heat capacity of air, J/(m^3 K) (1.1614 kg/m^3 times 1007
/// J/(kg K), Incropera Table A.4 at 300 K).
const AIR_HEAT_CAPACITY: f64 = 1.1614 * 1007.0;
/// Latent heat of vaporisation of water near 20-30 °C, J/kg.
const LATENT_HEAT: f64 = 2.45e6;
/// Molar mass of water, kg/mol, and the gas constant, J/(mol K).
const WATER_MOLAR_MASS: f64 = 0.018_015;
const GAS_CONSTANT: f64 = 8.314_462;

/// Room air when the stage does not say: 20 °C, still, 50 % humidity.
pub const ROOM_TEMPERATURE: f64 = 20.0;
pub const ROOM_AIR_SPEED: f64 = 0.0;
pub const ROOM_HUMIDITY: f64 = 0.5;
/// A hand-held dryer's air on its axis: 10 m/s at 60 °C (hot setting).
pub const BLOWER_AIR_SPEED: f64 = 10.0;
pub const BLOWER_AIR_TEMPERATURE: f64 = 60.0;

/// Entries of the time-constant table over the blower's reach 0..1.
const REACH_TABLE: usize = 257;

/// Saturated vapour pressure over water, Pa, at `celsius` (Alduchov and
/// Eskridge 1996, their AERK form of the Magnus formula).
pub fn saturation_pressure(celsius: f64) -> f64 {
    610.94 * (17.625 * celsius / (celsius + 243.04)).exp()
}

/// Vapour density, kg/m^3, of vapour at `pressure` Pa and `celsius`.
fn vapour_density(pressure: f64, celsius: f64) -> f64 {
    pressure * WATER_MOLAR_MASS / (GAS_CONSTANT * (celsius + 273.15))
}

/// Sherwood number of a cylinder in cross flow at Reynolds number `re`
/// (Churchill and Bernstein 1977, for `Re Sc > 0.2`; 0.3 in still air).
pub fn sherwood(re: f64) -> f64 {
    let sc = AIR_VISCOSITY / VAPOUR_DIFFUSIVITY;
    let laminar = 0.62 * re.sqrt() * sc.cbrt() / (1.0 + (0.4 / sc).powf(2.0 / 3.0)).powf(0.25);
    0.3 + laminar * (1.0 + (re / 282_000.0).powf(5.0 / 8.0)).powf(4.0 / 5.0)
}

/// The wet fibre's surface temperature, °C: where the heat the air brings,
/// `h (T_a - T_s)`, is the heat evaporation takes, `h_m L (rho_s(T_s) -
/// rho_v)`, with `h / h_m = rho c_p Le^(2/3)` (Chilton-Colburn). Found by
/// bisection between the dew point's side and the air temperature.
pub fn wet_bulb(air: f64, vapour: f64) -> f64 {
    let lewis = AIR_THERMAL_DIFFUSIVITY / VAPOUR_DIFFUSIVITY;
    let ratio = AIR_HEAT_CAPACITY * lewis.powf(2.0 / 3.0);
    let balance = |ts: f64| {
        ratio * (air - ts) - LATENT_HEAT * (vapour_density(saturation_pressure(ts), ts) - vapour)
    };
    let (mut low, mut high) = (-60.0f64, air);
    for _ in 0..60 {
        let mid = 0.5 * (low + high);
        if balance(mid) > 0.0 {
            low = mid;
        } else {
            high = mid;
        }
    }
    0.5 * (low + high)
}

/// The drying time constant, seconds, of a wet fibre of `radius` m and
/// `density` kg/m^3 in air at `celsius` moving at `speed` m/s past it,
/// carrying `vapour` kg/m^3 of water vapour. Infinite when the air cannot
/// take more water.
pub fn time_constant(radius: f64, density: f64, celsius: f64, speed: f64, vapour: f64) -> f64 {
    let re = speed.max(0.0) * 2.0 * radius / AIR_VISCOSITY;
    let surface = wet_bulb(celsius, vapour);
    let deficit = vapour_density(saturation_pressure(surface), surface) - vapour;
    if deficit <= 0.0 {
        return f64::INFINITY;
    }
    WATER_UPTAKE * density * radius * radius / (sherwood(re) * VAPOUR_DIFFUSIVITY * deficit)
}

/// The air of a drying stage: the room's, and the blower's where it
/// reaches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DryingAir {
    pub temperature: f64,
    pub speed: f64,
    pub humidity: f64,
    /// The blower's air on its axis: speed (m/s) and temperature (°C).
    pub blower: Option<(f64, f64)>,
}

impl DryingAir {
    /// The drying air of a `dry` stage that has no `drying_time` (which
    /// drives the hair dry over that time instead); `None` otherwise.
    pub fn of_stage(spec: &StageSpec) -> Option<DryingAir> {
        if *spec.kind.get_ref() != super::schema::StageKind::Dry || spec.drying_time.is_some() {
            return None;
        }
        let value = |v: &Option<serde_spanned::Spanned<f64>>, default: f64| {
            v.as_ref().map_or(default, |v| *v.get_ref())
        };
        Some(DryingAir {
            temperature: value(&spec.air_temperature, ROOM_TEMPERATURE),
            speed: value(&spec.air_speed, ROOM_AIR_SPEED),
            humidity: value(&spec.humidity, ROOM_HUMIDITY),
            blower: spec.blower.as_ref().map(|b| {
                let b = b.get_ref();
                (
                    b.air_speed.unwrap_or(BLOWER_AIR_SPEED),
                    b.air_temperature.unwrap_or(BLOWER_AIR_TEMPERATURE),
                )
            }),
        })
    }

    /// The room air's vapour density, kg/m^3 (the blower heats room air:
    /// the same vapour).
    fn vapour(&self) -> f64 {
        self.humidity.clamp(0.0, 1.0)
            * vapour_density(saturation_pressure(self.temperature), self.temperature)
    }

    /// The time constant where the blower's air reaches with `reach` in
    /// 0..1 (0: room air only).
    pub fn time_constant(&self, radius: f64, density: f64, reach: f64) -> f64 {
        let (speed, celsius) = match self.blower {
            Some((speed, celsius)) => (
                self.speed + reach * speed,
                self.temperature + reach * (celsius - self.temperature),
            ),
            None => (self.speed, self.temperature),
        };
        time_constant(radius, density, celsius, speed, self.vapour())
    }
}

/// A stage's drying, ready to step: `1 - exp(-dt / tau)` tabled over the
/// blower's reach (the time constant needs a root-finding; the table keeps
/// a step's cost to a lookup per vertex).
#[derive(Debug, Clone)]
pub struct Drying {
    blower: Option<Blower>,
    /// Fraction of the water that leaves in one step, at reach k / (n - 1).
    loss: Vec<f64>,
    /// Hydrogen re-formed per vertex this step (the water that left).
    pub reform: Vec<f32>,
}

impl Drying {
    pub fn new(
        air: &DryingAir,
        blower: Option<Blower>,
        radius: f64,
        density: f64,
        dt: f64,
    ) -> Drying {
        let entries = if blower.is_some() { REACH_TABLE } else { 1 };
        let loss = (0..entries)
            .map(|k| {
                let reach = k as f64 / (REACH_TABLE - 1) as f64;
                let tau = air.time_constant(radius, density, reach);
                -(-dt / tau).exp_m1()
            })
            .collect();
        Drying {
            blower,
            loss,
            reform: Vec::new(),
        }
    }

    /// One step: each vertex's wetness falls by its loss; `reform` gets the
    /// water that left, for the solver to re-form hydrogen bonds by.
    pub fn step(&mut self, positions: &[[f32; 3]], wetness: &mut [f32]) {
        self.reform.clear();
        for (w, &p) in wetness.iter_mut().zip(positions) {
            let loss = match &self.blower {
                Some(b) => {
                    let x = f64::from(crate::sim::blower_reach(b, p)) * (REACH_TABLE - 1) as f64;
                    let k = (x.floor() as usize).min(REACH_TABLE - 2);
                    let t = x - k as f64;
                    self.loss[k] + t * (self.loss[k + 1] - self.loss[k])
                }
                None => self.loss[0],
            };
            let before = *w;
            *w = (f64::from(before) * (1.0 - loss)) as f32;
            self.reform.push(before - *w);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_saturation_pressure_and_wet_bulb_match_the_tables() {
        // 2339 Pa at 20 °C and 19 946 Pa at 60 °C (steam tables); the
        // Magnus form is within 0.5 % over 0-60 °C.
        assert!((saturation_pressure(20.0) / 2339.0 - 1.0).abs() < 0.005);
        assert!((saturation_pressure(60.0) / 19_946.0 - 1.0).abs() < 0.01);
        // Psychrometric chart: 20 °C at 50 % relative humidity has a wet
        // bulb of 13.7 °C.
        let vapour = 0.5 * vapour_density(saturation_pressure(20.0), 20.0);
        let wb = wet_bulb(20.0, vapour);
        assert!((wb - 13.7).abs() < 0.6, "wet bulb {wb}");
    }

    #[test]
    fn a_blower_dries_a_fibre_in_a_second_and_still_air_in_tens_of_seconds() {
        let room = DryingAir {
            temperature: 20.0,
            speed: 0.0,
            humidity: 0.5,
            blower: Some((10.0, 60.0)),
        };
        let still = room.time_constant(4e-5, 1300.0, 0.0);
        let blown = room.time_constant(4e-5, 1300.0, 1.0);
        eprintln!(
            "tau: still air {still:.2} s, half reach {:.2} s, on the axis {blown:.3} s",
            room.time_constant(4e-5, 1300.0, 0.5)
        );
        assert!((15.0..60.0).contains(&still), "still air: {still} s");
        assert!(
            (0.1..1.0).contains(&blown),
            "on the blower's axis: {blown} s"
        );
        // Warmer or faster air dries faster.
        assert!(room.time_constant(4e-5, 1300.0, 0.5) < still);
        let warm = DryingAir {
            temperature: 30.0,
            ..room
        };
        assert!(warm.time_constant(4e-5, 1300.0, 0.0) < still);
    }
}
