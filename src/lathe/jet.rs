//! Second-order jets in two variables: a value with its exact gradient and Hessian, carried
//! through arithmetic (forward-mode automatic differentiation).
//!
//! Every analytic lens surface is written once, as its sag formula `z(x, y)`, and evaluated on
//! jets: the compensation needs the normal (first derivatives) and its rate of change (second
//! derivatives, through the Weingarten equations), and hand-derived Hessians of a conic plus
//! a Zernike expansion are where bugs hide. A jet is six `f64`s and `Copy`; `num-dual`'s
//! `Dual2Vec` would do the same generically over nalgebra's allocators and pin our nalgebra
//! version to its own, for no gain at two variables.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// `f(x, y)` with `∂f/∂x, ∂f/∂y` and `∂²f/∂x², ∂²f/∂x∂y, ∂²f/∂y²` at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet2 {
    /// The value.
    pub value: f64,
    /// `[∂f/∂x, ∂f/∂y]`.
    pub gradient: [f64; 2],
    /// `[∂²f/∂x², ∂²f/∂x∂y, ∂²f/∂y²]`.
    pub hessian: [f64; 3],
}

impl Jet2 {
    /// A constant.
    pub fn constant(value: f64) -> Jet2 {
        Jet2 {
            value,
            gradient: [0.0; 2],
            hessian: [0.0; 3],
        }
    }

    /// The variables themselves at `(x, y)`.
    pub fn variables(x: f64, y: f64) -> (Jet2, Jet2) {
        (
            Jet2 {
                value: x,
                gradient: [1.0, 0.0],
                hessian: [0.0; 3],
            },
            Jet2 {
                value: y,
                gradient: [0.0, 1.0],
                hessian: [0.0; 3],
            },
        )
    }

    /// `g(self)` by the chain rule, given `g`, `g'` and `g''` at the value.
    fn chain(self, g: f64, dg: f64, ddg: f64) -> Jet2 {
        let [a, b] = self.gradient;
        let [h0, h1, h2] = self.hessian;
        Jet2 {
            value: g,
            gradient: [dg * a, dg * b],
            hessian: [
                ddg * a * a + dg * h0,
                ddg * a * b + dg * h1,
                ddg * b * b + dg * h2,
            ],
        }
    }

    /// The square root (NaN below zero, as `f64::sqrt`).
    pub fn sqrt(self) -> Jet2 {
        let s = self.value.sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * self.value))
    }

    /// The reciprocal.
    pub fn recip(self) -> Jet2 {
        let r = 1.0 / self.value;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }

    /// `self * self`.
    pub fn square(self) -> Jet2 {
        self * self
    }

    /// `selfⁿ` by repeated squaring (n ≥ 0).
    pub fn powi(self, n: u32) -> Jet2 {
        let mut result = Jet2::constant(1.0);
        let mut base = self;
        let mut n = n;
        while n > 0 {
            if n & 1 == 1 {
                result = result * base;
            }
            base = base * base;
            n >>= 1;
        }
        result
    }
}

impl Add for Jet2 {
    type Output = Jet2;
    fn add(self, o: Jet2) -> Jet2 {
        Jet2 {
            value: self.value + o.value,
            gradient: [
                self.gradient[0] + o.gradient[0],
                self.gradient[1] + o.gradient[1],
            ],
            hessian: [
                self.hessian[0] + o.hessian[0],
                self.hessian[1] + o.hessian[1],
                self.hessian[2] + o.hessian[2],
            ],
        }
    }
}

impl Neg for Jet2 {
    type Output = Jet2;
    fn neg(self) -> Jet2 {
        self * -1.0
    }
}

impl Sub for Jet2 {
    type Output = Jet2;
    fn sub(self, o: Jet2) -> Jet2 {
        self + (-o)
    }
}

impl Mul for Jet2 {
    type Output = Jet2;
    fn mul(self, o: Jet2) -> Jet2 {
        let (a, b) = (self, o);
        let [ax, ay] = a.gradient;
        let [bx, by] = b.gradient;
        Jet2 {
            value: a.value * b.value,
            gradient: [a.value * bx + b.value * ax, a.value * by + b.value * ay],
            hessian: [
                a.hessian[0] * b.value + 2.0 * ax * bx + a.value * b.hessian[0],
                a.hessian[1] * b.value + ax * by + ay * bx + a.value * b.hessian[1],
                a.hessian[2] * b.value + 2.0 * ay * by + a.value * b.hessian[2],
            ],
        }
    }
}

impl Div for Jet2 {
    type Output = Jet2;
    #[allow(clippy::suspicious_arithmetic_impl)] // a / b = a · (1/b), by the chain rule
    fn div(self, o: Jet2) -> Jet2 {
        self * o.recip()
    }
}

impl Add<f64> for Jet2 {
    type Output = Jet2;
    fn add(mut self, c: f64) -> Jet2 {
        self.value += c;
        self
    }
}

impl Sub<f64> for Jet2 {
    type Output = Jet2;
    fn sub(self, c: f64) -> Jet2 {
        self + (-c)
    }
}

impl Mul<f64> for Jet2 {
    type Output = Jet2;
    fn mul(self, c: f64) -> Jet2 {
        Jet2 {
            value: self.value * c,
            gradient: [self.gradient[0] * c, self.gradient[1] * c],
            hessian: [
                self.hessian[0] * c,
                self.hessian[1] * c,
                self.hessian[2] * c,
            ],
        }
    }
}

impl Div<f64> for Jet2 {
    type Output = Jet2;
    fn div(self, c: f64) -> Jet2 {
        self * (1.0 / c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central differences of `f` at `(x, y)`: gradient and Hessian.
    fn differences(f: impl Fn(f64, f64) -> f64, x: f64, y: f64) -> ([f64; 2], [f64; 3]) {
        let h = 1e-4;
        let fx = (f(x + h, y) - f(x - h, y)) / (2.0 * h);
        let fy = (f(x, y + h) - f(x, y - h)) / (2.0 * h);
        let fxx = (f(x + h, y) - 2.0 * f(x, y) + f(x - h, y)) / (h * h);
        let fyy = (f(x, y + h) - 2.0 * f(x, y) + f(x, y - h)) / (h * h);
        let fxy =
            (f(x + h, y + h) - f(x + h, y - h) - f(x - h, y + h) + f(x - h, y - h)) / (4.0 * h * h);
        ([fx, fy], [fxx, fxy, fyy])
    }

    #[test]
    fn a_conic_sag_matches_its_differences() {
        // z = c r² / (1 + √(1 − (1 + k) c² r²)) + a r⁴ y / (1 + x²)
        let (c, k, a) = (1.0 / 37.0, -0.6, 3e-5);
        let plain = |x: f64, y: f64| {
            let r2 = x * x + y * y;
            c * r2 / (1.0 + (1.0 - (1.0 + k) * c * c * r2).sqrt()) + a * r2 * r2 * y / (1.0 + x * x)
        };
        let jet = |x: f64, y: f64| {
            let (x, y) = Jet2::variables(x, y);
            let r2 = x.square() + y.square();
            r2 * c / ((-(r2 * ((1.0 + k) * c * c)) + 1.0).sqrt() + 1.0)
                + r2.square() * y * a / (x.square() + 1.0)
        };
        for &(x, y) in &[(0.0, 0.0), (3.0, -2.0), (-11.0, 7.5), (14.0, 14.0)] {
            let j = jet(x, y);
            let (g, h) = differences(plain, x, y);
            assert!((j.value - plain(x, y)).abs() < 1e-15);
            for i in 0..2 {
                assert!((j.gradient[i] - g[i]).abs() < 1e-8, "{x},{y}: {j:?} {g:?}");
            }
            for i in 0..3 {
                assert!((j.hessian[i] - h[i]).abs() < 1e-5, "{x},{y}: {j:?} {h:?}");
            }
        }
    }

    #[test]
    fn powers_agree_with_products() {
        let (x, y) = Jet2::variables(1.3, -0.7);
        let p = x * y + 2.0;
        let by_product = p * p * p * p * p;
        let by_power = p.powi(5);
        assert!((by_product.value - by_power.value).abs() < 1e-12);
        for i in 0..3 {
            assert!((by_product.hessian[i] - by_power.hessian[i]).abs() < 1e-10);
        }
        assert_eq!(p.powi(0), Jet2::constant(1.0));
    }
}
